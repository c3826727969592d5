"""Forward shading: triangles drawn in submission order, each fragment shaded if it passes the
depth test at the moment it is drawn.

The draw is replayed from the fragment list: sorted so that each pixel's fragments are in
triangle (submission) order, and a segmented running minimum of the depth written so far
decides which pass (GL_LESS). One sample sorts by (2x2 quad, triangle, lane): each pixel's
fragments in order, and the units of one (triangle, quad) together, which counts the quads
without a second sort; several samples sort by (sample, pixel, triangle). With ``z_prepass``
a depth-only pass first fills the depth buffer (honouring the alpha test), then only
fragments at exactly that depth are shaded (GL_EQUAL): one shade per visible pixel, while the
2x2 quads still launch helper lanes. Under MSAA the depth test runs per sample and the shader
once per (pixel, triangle) with any sample passing,
at the pixel centre; samples are resolved by averaging.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
import jaxrender.raster.samples as sample_patterns
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.dispatch import dispatch_lanes
from jaxrender.pipelines.draw_waves import draw_waves
from jaxrender.pipelines.micro_batch import triangle_batches
from jaxrender.pipelines.quads import BIG, first_units_of_quads, quad_list
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.forward_draw import (DrawList, any_per_unit, draw_list, fragment_lists,
                                              live_count, live_rows, pixel_exclusive_cummin,
                                              replay, single_sample_draw_list,
                                              sorted_and_replayed)
from jaxrender.pipelines.forward_transparency import forward_faces, forward_transparent
from jaxrender.pipelines.transparency import merge_counts
from jaxrender.pipelines.visibility import (clip_vertices, is_alpha_tested, points_at,
                                            points_at_xy)
from jaxrender.pipelines.waves import check_wave_size
from jaxrender.raster.fragments import Fragments
from jaxrender.shading import alpha_test, shade
from jaxrender.sorting import on_prefix
from jaxrender.types import Array, Frame

INF = float("inf")


@dataclass(frozen=True)
class ForwardConfig(BlendingConfig):
    """z_prepass: depth pre-pass then depth-equal shading. msaa: 1, 2, 4 or 8 samples (D3D
    standard positions). shade_helpers: run the shader on quad helper lanes too, as hardware
    does for derivatives (the image is unchanged: derivatives here are analytic; only the work
    grows, as ``counts["shader_evaluations"]`` shows: the live lanes the shader ran on).
    wave_size: lanes per wave (32 or 64) for the wave counts (the quads of one draw are packed
    into waves in rasterization order, as hardware launches them). sort_transparent: blend
    the transparent fragments sorted back to front per pixel (false: in submission order, as
    an unsorted engine would, order errors and all)."""

    z_prepass: bool = False
    msaa: int = 1
    shade_helpers: bool = False
    wave_size: int = 32
    sort_transparent: bool = True

    def __post_init__(self):
        super().__post_init__()
        if self.msaa not in (1, 2, 4, 8):
            raise ValueError(f"msaa must be 1, 2, 4 or 8, got {self.msaa}")
        check_wave_size(self.wave_size)
        if not self.sort_transparent and self.oit == "weighted":
            raise ValueError("sort_transparent = false has no effect with oit = \"weighted\" "
                             "(no order at all); set oit = \"sorted\"")


def alpha_pass(scene, draw: DrawList, unit_points, cfg) -> tuple[Array, Array]:
    """The fragments that survive the alpha test, and the alpha-test invocations. Only a
    fragment in front of every earlier opaque fragment of its pixel can pass the depth test,
    so only those are alpha-tested."""
    valid = draw.valid
    if not scene.effects.alpha_test:
        return valid, jnp.int32(0)

    def alpha_candidates(rows, _):
        d = draw._replace(**rows)
        tested = is_alpha_tested(scene, d.tri) & d.valid
        z_opaque = pixel_exclusive_cummin(d, jnp.where(d.valid & ~tested, d.depth, INF))
        return (tested, any_per_unit(d, tested & (d.depth < z_opaque))), None

    (tested, need), _ = on_prefix(alpha_candidates, live_count(draw), live_rows(draw))
    keep_u, work = dispatch.shade(
        dispatch.WorkList.of(need), unit_points,
        lambda pts: alpha_test(pts, scene).astype(jnp.float32),
        jnp.zeros((draw.tri.shape[0],), jnp.float32), cfg.chunk)
    return valid & (~tested | (keep_u[draw.unit] > 0.5)), work.invocations


@register_frame("forward", ForwardConfig)
def frame(scene, camera, cfg: ForwardConfig) -> Frame:
    """Forward shading in submission order (overdraw, 2x2 quads, optional Z pre-pass, MSAA),
    the opaque geometry first, then the transparent geometry blended over it."""
    offsets = sample_patterns.msaa(cfg.msaa) if cfg.msaa > 1 else sample_patterns.CENTER
    n_s = len(offsets)
    clip = clip_vertices(scene, camera, cfg)
    with jax.named_scope("fragments"):
        lists = fragment_lists(clip, offsets, cfg, forward_faces(scene, cfg))
        replayed = None
        if n_s == 1 and not scene.effects.alpha_test:
            # Nothing is alpha-tested between the sort and the depth test: one branch for both.
            draw, replayed = sorted_and_replayed(lists[0], scene.faces.shape[0], cfg)
        else:
            draw = draw_list(lists, cfg, scene.faces.shape[0])

    def unit_points(items):
        return points_at(scene, camera, clip, cfg, draw.tri[items], draw.pixel[items])

    with jax.named_scope("alpha_test"):
        keep, alpha_invocations = alpha_pass(scene, draw, unit_points, cfg)
    with jax.named_scope("depth_test"):
        if replayed is None:
            replayed = replay(draw, keep, n_s, cfg)
        shade_unit, win, first, work, per_pixel, z_final = replayed
    with jax.named_scope("quads"):
        if first is None:  # the helper lanes need the quads listed
            ql = quad_list(draw.tri, draw.pixel, shade_unit, cfg.width, cfg.height,
                           scene.faces.shape[0], live=draw.fragments if n_s == 1 else None)
            quads = (ql["start"], ql["tri"], ql["n_quads"])
        else:
            quads = (first, draw.tri, jnp.sum(first, dtype=jnp.int32))
    with jax.named_scope("shade"):
        colours = jnp.zeros((draw.tri.shape[0], 3), jnp.float32)
        if cfg.shade_helpers:
            colours, work = dispatch_lanes(
                ql["n_quads"] * 4, _helper_lane_fn(scene, camera, clip, cfg, ql), colours,
                cfg.chunk, 4 * colours.shape[0])  # a quad holds one fragment at least
        else:
            colours, work = dispatch.shade(work, unit_points, lambda p: shade(p, scene),
                                           colours, cfg.chunk)
    with jax.named_scope("resolve"):
        image, covered = resolve_samples(colours, draw, win, n_s, cfg)
    image, transparent, fr_t, front_t = forward_transparent(scene, camera, clip, image, z_final,
                                                            cfg)
    with jax.named_scope("counts"):
        invocations, fragments = work.invocations, draw.fragments
        if transparent is not None:  # the transparent pass's quads join the opaque pass's
            invocations = invocations + transparent["transparent_invocations"]
            fragments = fragments + fr_t.count
            quads = joined_quads(quads, fr_t, front_t, cfg, scene.faces.shape[0])
            per_pixel = per_pixel.at[jnp.where(front_t, fr_t.pixel, per_pixel.shape[0])].add(
                1, mode="drop")
        counts = _counts(scene, draw, quads, invocations, fragments, covered, alpha_invocations,
                         cfg)
        # The pre-pass transforms every vertex again (positions only).
        counts.update(vertex_counts(scene, full_passes=1, position_passes=int(cfg.z_prepass)))
        if transparent is not None:
            counts = merge_counts(counts, transparent, shading_counted=True)
    image = poison_on_overflow(image, counts["overflow"])
    return Frame(image, counts, {"shade_count": per_pixel.reshape(cfg.height, cfg.width)})


def joined_quads(quads, fr, front, cfg, n_tris: int):
    """``quads`` (the opaque pass's: bool[N] one unit of each quad marked, int32[N] its
    triangle, quad count) with the quads of the transparent fragments in front (a fragment
    list and bool[F]): the units grouped by (2x2 quad, triangle) as the draw list groups them."""
    start, tri, n_quads = quads
    listed = single_sample_draw_list(Fragments(fr.pixel, fr.tri, fr.depth, front, fr.count),
                                     cfg.width, cfg.height, n_tris)
    first = first_units_of_quads(listed.tri, listed.seg, listed.valid)
    return (jnp.concatenate([start, first]), jnp.concatenate([tri, listed.tri]),
            n_quads + jnp.sum(first, dtype=jnp.int32))


def resolve_samples(colours, draw: DrawList, win, n_s: int, cfg):
    """Each (sample, pixel) shows its winning fragment's unit colour; samples are averaged.
    Returns (image float32[H, W, 3], covered pixels int32)."""
    h, w = cfg.height, cfg.width
    has = win >= 0
    c = jnp.where(has[:, None], colours[draw.unit[jnp.maximum(win, 0)]], 0.0)
    image = jnp.mean(c.reshape(n_s, h, w, 3), axis=0)
    covered = jnp.sum(jnp.any(has.reshape(n_s, h * w), axis=0), dtype=jnp.int32)
    return image, covered


def _counts(scene, draw: DrawList, quads, invocations, fragments, covered, alpha_invocations,
            cfg) -> dict:
    """``quads``: (bool[N] one unit of each quad marked, int32[N] its triangle, quad count).
    Waves: the quads of one draw, in rasterization order (``draw_waves``)."""
    quad_start, quad_tri, n_quads = quads
    lanes = n_quads * 4
    return make_counts(
        shade_invocations=invocations,
        helper_lanes=lanes - invocations,
        covered_pixels=covered,
        **draw_waves(triangle_batches(scene.tri_object, scene.tri_material), quad_start,
                     quad_tri, cfg.wave_size, invocations),
        quads=n_quads,
        # The shader's live lanes: the shaded units, plus the helper lanes when they run.
        shader_evaluations=lanes if cfg.shade_helpers else invocations,
        fragments=fragments,
        alpha_invocations=alpha_invocations,
        overflow=draw.overflow,
    )


render = REGISTRY["forward"].render  # the compiled, overflow-checked entry


def _helper_lane_fn(scene, camera, clip, cfg, ql):
    """Lane ``4 q + k`` is pixel k of quad q; it writes the colour of its unit if the unit is
    shaded, and otherwise runs as a helper lane (its result is dropped)."""
    qw = (cfg.width + 1) // 2
    n_frag = ql["tri"].shape[0]

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
