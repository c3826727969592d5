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
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
import jaxrender.raster.samples as sample_patterns
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.dispatch import dispatch_lanes
from jaxrender.pipelines.draw_waves import draw_waves
from jaxrender.pipelines.micro_batch import triangle_batches
from jaxrender.pipelines.quads import (BIG, exclusive_lane_cummin, exclusive_segmented_cummin,
                                       first_of_segment_index, first_units_of_quads, quad_keys,
                                       quad_list, segment_starts)
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.forward_transparency import forward_faces, forward_transparent
from jaxrender.pipelines.transparency import merge_counts
from jaxrender.pipelines.visibility import (clip_vertices, is_alpha_tested, points_at,
                                            points_at_xy, raster_fragments)
from jaxrender.pipelines.waves import check_wave_size
from jaxrender.raster.fragments import Fragments
from jaxrender.shading import alpha_test, shade
from jaxrender.sorting import EMPTY, lex_sort, on_prefix
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


class DrawList(NamedTuple):
    """The fragments of every sample in draw order, empty entries last: sorted by (sample,
    pixel, triangle), ``seg`` marking each (sample, pixel)'s first fragment; or, with ``lane``
    (one sample), by (2x2 quad, triangle, lane), ``seg`` marking each quad's first fragment and
    ``lane`` the pixel's place in its quad (each pixel's fragments still in triangle order,
    interleaved with its quad's other pixels'). ``slot`` is the fragment's (sample, pixel)
    (S * P when empty), ``unit`` the fragment that represents its (triangle, pixel) shading
    unit (under MSAA several samples share one), ``samples`` the sample count."""

    skey: Array
    pixel: Array
    tri: Array
    depth: Array
    valid: Array
    seg: Array
    slot: Array
    unit: Array
    overflow: Array
    fragments: Array
    samples: int = 1
    lane: Array | None = None


def draw_list(scene, clip, offsets, cfg: ForwardConfig, faces: Array) -> DrawList:
    """The draw of ``faces`` (the scene's, some made degenerate) replayed from the fragment
    lists of every sample offset."""
    lists = [raster_fragments(clip, faces, cfg, cull_backfaces=cfg.cull_backfaces,
                              sample_offset=o) for o in offsets]
    n_pix, n_tris = cfg.width * cfg.height, scene.faces.shape[0]
    if len(lists) == 1:
        return single_sample_draw_list(lists[0], cfg.width, cfg.height, n_tris)
    return sorted_draw_list(lists, n_pix, n_tris)


def sorted_draw_list(lists, n_pix: int, n_tris: int) -> DrawList:
    """The DrawList of one fragment list per sample, each of the same capacity."""
    n_s, cap = len(lists), lists[0].pixel.shape[0]
    cat = lambda f: jnp.concatenate([getattr(fr, f) for fr in lists])  # noqa: E731
    valid = cat("valid")
    samp = jnp.concatenate([jnp.full((cap,), s, jnp.int32) for s in range(n_s)])
    skey = jnp.where(valid, samp, n_s)
    # Draw order: per (sample, pixel), triangles in submission order; empty entries last.
    (skey, pixel, tri), (depth,) = lex_sort(
        (skey, cat("pixel"), cat("tri")), (n_s, n_pix - 1, n_tris - 1), (cat("depth"),))
    valid = skey < n_s
    overflow = sum(fr.overflowed.astype(jnp.int32) for fr in lists)
    n_fragments = sum(fr.count for fr in lists)
    seg = segment_starts(skey, pixel)
    slot = jnp.where(valid, skey * n_pix + pixel, n_s * n_pix)
    unit = _units(tri, pixel, valid, n_s, n_tris, n_pix)
    return DrawList(skey, pixel, tri, depth, valid, seg, slot, unit, overflow, n_fragments, n_s)


def single_sample_draw_list(fr, width: int, height: int, n_tris: int) -> DrawList:
    """The DrawList of one sample's fragment list, quad-major: sorted by (2x2 quad, triangle,
    lane), so that the units of one (triangle, quad) lie together and the quads are counted
    without a second sort (``quads.first_units_of_quads``). Its fragments are a prefix of the
    list, so only that prefix is keyed, sorted and read (``on_prefix``): the fields past it are
    those of empty entries."""
    n_pix, qw = width * height, (width + 1) // 2
    live = jnp.minimum(fr.count, fr.pixel.shape[0])
    n_quads = qw * ((height + 1) // 2)

    def sort_prefix(part, _):
        pixel, tri, depth, valid = part
        quad, lane = quad_keys(jnp.where(valid, pixel, 0), width)
        # (triangle, lane) as one key: one out-of-range code where two took a bit each, so
        # that room's key fits 32 bits (a 32-bit pairs sort, half the radix passes of a
        # 64-bit one).
        keys = [jnp.where(valid, k, -1) for k in (quad, tri * 4 + lane)]
        (quad, tri_lane), (depth,) = lex_sort(keys, (n_quads - 1, 4 * n_tris - 1), (depth,))
        valid = quad != EMPTY
        quad, lane = jnp.where(valid, quad, 0), jnp.where(valid, tri_lane % 4, 0)
        pixel = (2 * (quad // qw) + lane // 2) * width + 2 * (quad % qw) + lane % 2
        skey = jnp.where(valid, 0, 1)
        return {"skey": skey, "pixel": pixel, "tri": jnp.where(valid, tri_lane // 4, EMPTY),
                "depth": depth, "valid": valid, "seg": segment_starts(skey, quad),
                "slot": jnp.where(valid, pixel, n_pix), "lane": lane}, None

    empty = {"skey": 1, "pixel": 0, "tri": EMPTY, "depth": 0.0, "valid": False, "seg": False,
             "slot": n_pix, "lane": 0}
    d, _ = on_prefix(sort_prefix, live, (fr.pixel, fr.tri, fr.depth, fr.valid), fill=empty)
    return DrawList(**d, unit=jnp.arange(fr.pixel.shape[0], dtype=jnp.int32),
                    overflow=fr.overflowed.astype(jnp.int32), fragments=fr.count, samples=1)


def pixel_exclusive_cummin(draw: DrawList, values: Array) -> Array:
    """float32[F]: the minimum of the values of the earlier fragments of the same (sample,
    pixel), +inf for its first: what a depth buffer held when the fragment was drawn."""
    if draw.lane is None:
        return exclusive_segmented_cummin(values, draw.seg)
    return exclusive_lane_cummin(values, draw.seg, draw.lane)


def _units(tri, pixel, valid, n_s: int, n_tris: int, n_pix: int) -> Array:
    """The shader runs once per (triangle, pixel): under MSAA several sample fragments share
    one unit, represented by its first fragment."""
    n_frag = tri.shape[0]
    if n_s == 1:
        return jnp.arange(n_frag, dtype=jnp.int32)
    idx = jnp.arange(n_frag, dtype=jnp.int32)
    (t_b, p_b), (idx_b,) = lex_sort((jnp.where(valid, tri, BIG), pixel),
                                    (n_tris - 1, n_pix - 1), (idx,))
    rep = idx_b[first_of_segment_index(segment_starts(t_b, p_b))]
    return jnp.zeros((n_frag,), jnp.int32).at[idx_b].set(rep)


def _any_per_unit(draw: DrawList, flag: Array) -> Array:
    """bool[F]: the flag of any fragment of each fragment's shading unit (one sample: itself)."""
    if draw.samples == 1:
        return flag
    n_frag = draw.tri.shape[0]
    return jnp.zeros((n_frag,), jnp.int32).at[draw.unit].max(flag.astype(jnp.int32)) > 0


def live_rows(draw: DrawList) -> dict:
    """The draw list's per-fragment arrays, for ``on_prefix``: every fragment is in the first
    ``draw.fragments`` entries (the list is sorted with its empty entries last)."""
    fields = ("skey", "pixel", "tri", "depth", "valid", "seg", "slot", "unit", "lane")
    return {f: getattr(draw, f) for f in fields if getattr(draw, f) is not None}


def live_count(draw: DrawList) -> Array:
    return jnp.minimum(draw.fragments, draw.tri.shape[0])


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
        return (tested, _any_per_unit(d, tested & (d.depth < z_opaque))), None

    (tested, need), _ = on_prefix(alpha_candidates, live_count(draw), live_rows(draw))
    keep_u, work = dispatch.shade(
        dispatch.WorkList.of(need), unit_points,
        lambda pts: alpha_test(pts, scene).astype(jnp.float32),
        jnp.zeros((draw.tri.shape[0],), jnp.float32), cfg.chunk)
    return valid & (~tested | (keep_u[draw.unit] > 0.5)), work.invocations


def depth_test(draw: DrawList, keep: Array, n_s: int, cfg: ForwardConfig):
    """The plan: (units to shade bool[F], the fragment each (sample, pixel) shows int32[S * P],
    -1 for none, the final depth float32[S * P], +inf where none). GL_LESS in draw order, or
    GL_EQUAL against the pre-pass depth."""
    n_slots = n_s * cfg.width * cfg.height
    zk = jnp.where(keep, draw.depth, INF)
    zbuf = jnp.full((n_slots,), INF).at[draw.slot].min(zk, mode="drop")
    z_final = zbuf.at[draw.slot].get(mode="fill", fill_value=-INF)
    if cfg.z_prepass:
        shaded = draw.valid & (draw.depth == z_final)  # GL_EQUAL against the pre-pass depth
    else:
        shaded = draw.valid & (draw.depth < pixel_exclusive_cummin(draw, zk))  # GL_LESS
    writer = shaded & keep
    order = jnp.arange(draw.tri.shape[0], dtype=jnp.int32)
    win = jnp.full((n_slots,), -1, jnp.int32).at[draw.slot].max(
        jnp.where(writer, order, -1), mode="drop")
    return _any_per_unit(draw, shaded), win, zbuf


def replay(draw: DrawList, keep: Array, n_s: int, cfg):
    """The draw replayed over the list's filled prefix only (``on_prefix``): the depth test,
    the first unit of each (triangle, quad) when the sort already grouped them and each
    pixel's shade count; then the shading work list, compacted outside the branch (inside it
    was slower on foliage; RESULTS.md). Returns (shade_unit bool[F], win int32[S * P],
    first bool[F] or None, WorkList, per-pixel shades int32[P], the final depth
    float32[S * P], +inf where none)."""
    n_pix = cfg.width * cfg.height
    marks_quads = draw.lane is not None and not cfg.shade_helpers

    def run(rows, _):
        d = draw._replace(**rows["draw"])
        shade_unit, win, z_final = depth_test(d, rows["keep"], n_s, cfg)
        out = {"shade": shade_unit}
        if marks_quads:
            out["first"] = first_units_of_quads(d.tri, d.seg, shade_unit)
        per_pixel = jnp.zeros((n_pix,), jnp.int32).at[
            jnp.where(shade_unit, d.pixel, n_pix)].add(1, mode="drop")
        return out, (win, per_pixel, z_final)

    out, (win, per_pixel, z_final) = on_prefix(run, live_count(draw),
                                               {"draw": live_rows(draw), "keep": keep})
    return (out["shade"], win, out.get("first"), dispatch.WorkList.of(out["shade"]), per_pixel,
            z_final)


@register_frame("forward", ForwardConfig)
def frame(scene, camera, cfg: ForwardConfig) -> Frame:
    """Forward shading in submission order (overdraw, 2x2 quads, optional Z pre-pass, MSAA),
    the opaque geometry first, then the transparent geometry blended over it."""
    offsets = sample_patterns.msaa(cfg.msaa) if cfg.msaa > 1 else sample_patterns.CENTER
    n_s = len(offsets)
    clip = clip_vertices(scene, camera, cfg)
    with jax.named_scope("fragments"):
        draw = draw_list(scene, clip, offsets, cfg, forward_faces(scene, cfg))

    def unit_points(items):
        return points_at(scene, camera, clip, cfg, draw.tri[items], draw.pixel[items])

    with jax.named_scope("alpha_test"):
        keep, alpha_invocations = alpha_pass(scene, draw, unit_points, cfg)
    with jax.named_scope("depth_test"):
        shade_unit, win, first, work, per_pixel, z_final = replay(draw, keep, n_s, cfg)
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
