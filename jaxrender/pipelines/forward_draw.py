"""Forward's draw list, the fragments of every sample in draw order, and its replay: the depth
test in submission order (GL_LESS, or GL_EQUAL after a depth pre-pass), over the list's filled
prefix only."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.quads import (BIG, exclusive_lane_cummin, exclusive_segmented_cummin,
                                       first_of_segment_index, first_units_of_quads, quad_keys,
                                       segment_starts)
from jaxrender.pipelines.visibility import raster_fragments
from jaxrender.sorting import EMPTY, lex_sort, on_prefix
from jaxrender.types import Array

INF = float("inf")


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


def fragment_lists(clip, offsets, cfg, faces: Array) -> list:
    """The fragment list of ``faces`` (the scene's, some made degenerate) at each sample
    offset."""
    return [raster_fragments(clip, faces, cfg, cull_backfaces=cfg.cull_backfaces,
                             sample_offset=o) for o in offsets]


def draw_list(lists: list, cfg, n_tris: int) -> DrawList:
    """The draw replayed from the fragment lists of every sample offset."""
    if len(lists) == 1:
        return single_sample_draw_list(lists[0], cfg.width, cfg.height, n_tris)
    return sorted_draw_list(lists, cfg.width * cfg.height, n_tris)


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
    unit = shading_units(tri, pixel, valid, n_s, n_tris, n_pix)
    return DrawList(skey, pixel, tri, depth, valid, seg, slot, unit, overflow, n_fragments, n_s)


def quad_major_sort(width: int, height: int, n_tris: int):
    """(sort(rows, _) -> (fields, None), the fields of an empty entry) for ``on_prefix``: the
    prefix of a fragment list (pixel, tri, depth, valid) sorted by (2x2 quad, triangle, lane)
    into a DrawList's per-fragment fields."""
    n_pix, qw = width * height, (width + 1) // 2
    n_quads = qw * ((height + 1) // 2)

    def sort(part, _):
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
    return sort, empty


def single_sample_draw_list(fr, width: int, height: int, n_tris: int) -> DrawList:
    """The DrawList of one sample's fragment list, quad-major: sorted by (2x2 quad, triangle,
    lane), so that the units of one (triangle, quad) lie together and the quads are counted
    without a second sort (``quads.first_units_of_quads``). Its fragments are a prefix of the
    list, so only that prefix is keyed, sorted and read (``on_prefix``): the fields past it are
    those of empty entries."""
    sort, empty = quad_major_sort(width, height, n_tris)
    fields, _ = on_prefix(sort, _filled(fr), _fragment_rows(fr), fill=empty)
    return _drawn(fields, fr)


def _filled(fr) -> Array:
    return jnp.minimum(fr.count, fr.pixel.shape[0])


def _fragment_rows(fr) -> tuple:
    return fr.pixel, fr.tri, fr.depth, fr.valid


def _drawn(fields: dict, fr) -> DrawList:
    """The one-sample DrawList of the sorted ``fields`` of fragment list ``fr``."""
    return DrawList(**fields, unit=jnp.arange(fields["tri"].shape[0], dtype=jnp.int32),
                    overflow=fr.overflowed.astype(jnp.int32), fragments=fr.count, samples=1)


def pixel_exclusive_cummin(draw: DrawList, values: Array) -> Array:
    """float32[F]: the minimum of the values of the earlier fragments of the same (sample,
    pixel), +inf for its first: what a depth buffer held when the fragment was drawn."""
    if draw.lane is None:
        return exclusive_segmented_cummin(values, draw.seg)
    return exclusive_lane_cummin(values, draw.seg, draw.lane)


def shading_units(tri, pixel, valid, n_s: int, n_tris: int, n_pix: int) -> Array:
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


def any_per_unit(draw: DrawList, flag: Array) -> Array:
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


def depth_test(draw: DrawList, keep: Array, n_s: int, cfg):
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
    return any_per_unit(draw, shaded), win, zbuf


def replayed_rows(d: DrawList, keep: Array, n_s: int, cfg, marks_quads: bool):
    """The depth test of the rows of ``d`` (a prefix holding every fragment), the first unit
    of each (triangle, quad) when ``marks_quads`` and each pixel's shade count: (rows
    {"shade", "first"}, (win, per-pixel shades, final depth))."""
    n_pix = cfg.width * cfg.height
    shade_unit, win, z_final = depth_test(d, keep, n_s, cfg)
    out = {"shade": shade_unit}
    if marks_quads:
        out["first"] = first_units_of_quads(d.tri, d.seg, shade_unit)
    per_pixel = jnp.zeros((n_pix,), jnp.int32).at[
        jnp.where(shade_unit, d.pixel, n_pix)].add(1, mode="drop")
    return out, (win, per_pixel, z_final)


def _replay_result(out: dict, win, per_pixel, z_final) -> tuple:
    return (out["shade"], win, out.get("first"), dispatch.WorkList.of(out["shade"]), per_pixel,
            z_final)


def replay(draw: DrawList, keep: Array, n_s: int, cfg):
    """The draw replayed over the list's filled prefix only (``on_prefix``): the depth test,
    the first unit of each (triangle, quad) when the sort already grouped them and each
    pixel's shade count; then the shading work list, compacted outside the branch (inside it
    was slower on foliage; RESULTS.md). Returns (shade_unit bool[F], win int32[S * P],
    first bool[F] or None, WorkList, per-pixel shades int32[P], the final depth
    float32[S * P], +inf where none)."""
    marks_quads = draw.lane is not None and not cfg.shade_helpers

    def run(rows, _):
        return replayed_rows(draw._replace(**rows["draw"]), rows["keep"], n_s, cfg, marks_quads)

    out, rest = on_prefix(run, live_count(draw), {"draw": live_rows(draw), "keep": keep})
    return _replay_result(out, *rest)


def sorted_and_replayed(fr, n_tris: int, cfg) -> tuple[DrawList, tuple]:
    """``single_sample_draw_list`` and then ``replay`` with every fragment kept (no alpha
    test), in one branch of the list's filled prefix: one host read where there were two, and
    the sorted fields padded to the list's length once. Returns (DrawList, replay's result)."""
    sort, empty = quad_major_sort(cfg.width, cfg.height, n_tris)
    marks_quads = not cfg.shade_helpers

    def both(part, _):
        fields, _ = sort(part, None)
        out, rest = replayed_rows(_drawn(fields, fr), fields["valid"], 1, cfg, marks_quads)
        return {"draw": fields, "replay": out}, rest

    fill = {"draw": empty, "replay": {"shade": False, "first": False} if marks_quads
            else {"shade": False}}
    rows, rest = on_prefix(both, _filled(fr), _fragment_rows(fr), fill=fill)
    return _drawn(rows["draw"], fr), _replay_result(rows["replay"], *rest)
