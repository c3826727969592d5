"""Forward shading: triangles drawn in submission order, each fragment shaded if it passes the
depth test at the moment it is drawn.

The draw is replayed from the fragment list: fragments sorted by (sample, pixel, triangle) are
the per-pixel draw order, and a segmented running minimum of the depth written so far decides
which pass (GL_LESS). With ``z_prepass`` a depth-only pass first fills the depth buffer
(honouring the alpha test), then only fragments at exactly that depth are shaded (GL_EQUAL):
one shade per visible pixel, while the 2x2 quads still launch helper lanes. Under MSAA the
depth test runs per sample and the shader once per (pixel, triangle) with any sample passing,
at the pixel centre; samples are resolved by averaging.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp

from jaxrender.pipelines.base import (PipelineConfig, clip_vertices, dispatch_points,
                                      is_alpha_tested, make_counts, points_at,
                                      points_at_xy, poison_on_overflow,
                                      raster_fragments)
from jaxrender.pipelines.dispatch import dispatch_lanes
from jaxrender.pipelines.quads import (BIG, exclusive_segmented_cummin, first_of_segment_index,
                                       quad_list, segment_starts)
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.raster import samples as sample_patterns
from jaxrender.shading import alpha_test, shade
from jaxrender.sorting import lex_sort
from jaxrender.types import Frame

WAVE_SIZES = (32, 64)


@dataclass(frozen=True)
class ForwardConfig(PipelineConfig):
    """z_prepass: depth pre-pass then depth-equal shading. msaa: 1, 2, 4 or 8 samples (D3D
    standard positions). shade_helpers: run the shader on quad helper lanes too, as hardware
    does for derivatives (the image is unchanged: derivatives here are analytic; only the work
    grows, as ``counts["shader_evaluations"]`` shows: the live lanes the shader ran on).
    wave_size: lanes per wave (32 or 64) for the wave counts (quads of one material are packed
    into waves)."""

    z_prepass: bool = False
    msaa: int = 1
    shade_helpers: bool = False
    wave_size: int = 32

    def __post_init__(self):
        super().__post_init__()
        if self.msaa not in (1, 2, 4, 8):
            raise ValueError(f"msaa must be 1, 2, 4 or 8, got {self.msaa}")
        if self.wave_size not in WAVE_SIZES:
            raise ValueError(f"wave_size must be 32 or 64, got {self.wave_size}")


@register_frame("forward", ForwardConfig)
def frame(scene, camera, cfg: ForwardConfig) -> Frame:
    """Forward shading in submission order (overdraw, 2x2 quads, optional Z pre-pass, MSAA)."""
    w, h = cfg.width, cfg.height
    n_pix, cap = w * h, cfg.capacity
    offsets = sample_patterns.msaa(cfg.msaa) if cfg.msaa > 1 else sample_patterns.CENTER
    n_s = len(offsets)
    clip = clip_vertices(scene, camera, cfg)

    with jax.named_scope("fragments"):
        lists = [raster_fragments(clip, scene.faces, cfg, cull_backfaces=cfg.cull_backfaces,
                                  sample_offset=o) for o in offsets]
        cat = lambda f: jnp.concatenate([getattr(fr, f) for fr in lists])  # noqa: E731
        valid = cat("valid")
        samp = jnp.concatenate([jnp.full((cap,), s, jnp.int32) for s in range(n_s)])
        skey = jnp.where(valid, samp, n_s)
        # Draw order: per (sample, pixel), triangles in submission order; empty entries last.
        n_tris = scene.faces.shape[0]
        (skey, pixel, tri), (depth,) = lex_sort(
            (skey, cat("pixel"), cat("tri")), (n_s, n_pix - 1, n_tris - 1), (cat("depth"),))
        valid = skey < n_s
        n_frag = skey.shape[0]
        overflow = sum(fr.overflowed.astype(jnp.int32) for fr in lists)
        n_fragments = sum(fr.count for fr in lists)
        seg = segment_starts(skey, pixel)
        slot = jnp.where(valid, skey * n_pix + pixel, n_s * n_pix)

    with jax.named_scope("units"):
        # The shader runs once per (triangle, pixel): under MSAA several sample fragments share
        # one unit, represented by its first fragment.
        if n_s == 1:
            unit = jnp.arange(n_frag, dtype=jnp.int32)
        else:
            idx = jnp.arange(n_frag, dtype=jnp.int32)
            (t_b, p_b), (idx_b,) = lex_sort((jnp.where(valid, tri, BIG), pixel),
                                            (n_tris - 1, n_pix - 1), (idx,))
            rep = idx_b[first_of_segment_index(segment_starts(t_b, p_b))]
            unit = jnp.zeros((n_frag,), jnp.int32).at[idx_b].set(rep)

        def any_per_unit(flag):
            return jnp.zeros((n_frag,), jnp.int32).at[unit].max(flag.astype(jnp.int32)) > 0

        def unit_points(items):
            return points_at(scene, camera, clip, cfg, tri[items], pixel[items])

    inf = float("inf")
    with jax.named_scope("alpha_test"):
        tested = is_alpha_tested(scene, tri) & valid
        alpha_inv = jnp.int32(0)
        keep = valid
        if scene.effects.alpha_test:
            # Only a fragment in front of every earlier opaque fragment of its pixel can pass
            # the depth test, so only those are alpha-tested.
            z_opaque = exclusive_segmented_cummin(jnp.where(valid & ~tested, depth, inf), seg)
            need = any_per_unit(tested & (depth < z_opaque))
            keep_u, ac = dispatch_points(
                need, unit_points, lambda pts: alpha_test(pts, scene).astype(jnp.float32),
                jnp.zeros((n_frag,), jnp.float32), cfg.chunk)
            keep = valid & (~tested | (keep_u[unit] > 0.5))
            alpha_inv = ac["invocations"]

    with jax.named_scope("depth_test"):
        zk = jnp.where(keep, depth, inf)
        zbuf = jnp.full((n_s * n_pix,), inf).at[slot].min(zk, mode="drop")
        z_final = zbuf.at[slot].get(mode="fill", fill_value=-inf)
        if cfg.z_prepass:
            shaded = valid & (depth == z_final)  # GL_EQUAL against the pre-pass depth
        else:
            shaded = valid & (depth < exclusive_segmented_cummin(zk, seg))  # GL_LESS
        shade_unit = any_per_unit(shaded) if n_s > 1 else shaded
        writer = shaded & keep
        order = jnp.arange(n_frag, dtype=jnp.int32)
        win = jnp.full((n_s * n_pix,), -1, jnp.int32).at[slot].max(
            jnp.where(writer, order, -1), mode="drop")

    with jax.named_scope("quads"):
        ql = quad_list(tri, pixel, shade_unit, w, h, n_tris)
        n_quads = ql["n_quads"]

    with jax.named_scope("shade"):
        colours = jnp.zeros((n_frag, 3), jnp.float32)
        if cfg.shade_helpers:
            colours, dc = dispatch_lanes(n_quads * 4, _helper_lane_fn(scene, camera, clip, cfg,
                                                                      ql, n_frag),
                                         colours, cfg.chunk)
        else:
            colours, dc = dispatch_points(shade_unit, unit_points, lambda p: shade(p, scene),
                                          colours, cfg.chunk)
        invocations = dc["invocations"]

    with jax.named_scope("resolve"):
        has = win >= 0
        c = jnp.where(has[:, None], colours[unit[jnp.maximum(win, 0)]], 0.0)
        image = jnp.mean(c.reshape(n_s, h, w, 3), axis=0)
        covered = jnp.sum(jnp.any(has.reshape(n_s, n_pix), axis=0), dtype=jnp.int32)
        image = poison_on_overflow(image, overflow)

    with jax.named_scope("counts"):
        n_mat = scene.materials.albedo.shape[0]
        mat_q = scene.tri_material[jnp.where(ql["start"], ql["tri"], 0)]
        quads_per_mat = jnp.zeros((n_mat,), jnp.int32).at[mat_q].add(
            ql["start"].astype(jnp.int32))
        ws = cfg.wave_size
        waves = jnp.sum((quads_per_mat * 4 + ws - 1) // ws, dtype=jnp.int32)
        lanes = n_quads * 4
        per_pixel = jnp.zeros((n_pix,), jnp.int32).at[jnp.where(shade_unit, pixel, n_pix)].add(
            1, mode="drop")
        counts = make_counts(
            shade_invocations=invocations,
            helper_lanes=lanes - invocations,
            covered_pixels=covered,
            waves=waves,
            lane_utilization=invocations.astype(jnp.float32)
            / jnp.maximum(waves * ws, 1).astype(jnp.float32),
            quads=n_quads,
            # The shader's live lanes: the shaded units, plus the helper lanes when they run.
            shader_evaluations=lanes if cfg.shade_helpers else invocations,
            fragments=n_fragments,
            alpha_invocations=alpha_inv,
            overflow=overflow,
        )
    aux = {"shade_count": per_pixel.reshape(h, w)}
    return Frame(image, counts, aux)

render = REGISTRY["forward"].render  # the compiled, overflow-checked entry

def _helper_lane_fn(scene, camera, clip, cfg, ql, n_frag):
    """Lane ``4 q + k`` is pixel k of quad q; it writes the colour of its unit if the unit is
    shaded, and otherwise runs as a helper lane (its result is dropped)."""
    qw = (cfg.width + 1) // 2

    def fn(lanes, live):
        q, k = lanes // 4, lanes % 4
        s0 = ql["quad_start"][jnp.minimum(q, n_frag - 1)]
        t, quad = ql["tri"][s0], ql["quad"][s0]
        dest = jnp.full(lanes.shape, -1, jnp.int32)
        ok = jnp.zeros(lanes.shape, bool)
        for j in range(4):  # the <= 4 units of a quad are consecutive in the sorted list
            pos = jnp.minimum(s0 + j, n_frag - 1)
            m = (ql["live"][pos] & (ql["tri"][pos] == t) & (ql["quad"][pos] == quad)
                 & (ql["lane"][pos] == k) & (s0 + j < n_frag))
            dest = jnp.where(m, ql["order"][pos], dest)
            ok = ok | m
        px = 2 * (quad % qw) + k % 2
        py = 2 * (quad // qw) + k // 2
        t = jnp.where(live & (t != BIG), t, 0)
        pts = points_at_xy(scene, camera, clip, cfg, t, px, py)
        pts = dataclasses.replace(pts, valid=pts.valid & live)
        return dest, shade(pts, scene), ok

    return fn
