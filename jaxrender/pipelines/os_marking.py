"""Object-space shading, step 3: which shadels each visible pixel's filter footprint reads.

From the visibility buffer (so occluded surfaces mark nothing), each covered pixel's chart
coordinates and their screen derivatives give a MIP level per object (GL's LOD rule in the
object's level-0 shadels, plus a global bias); the filter taps there are the same ones the final
pass reads: 2x2 bilinear texels at one level (``bilinear``) or at two (``trilinear``), at
``aniso_taps`` positions along the footprint's major axis. LOD and filter fractions are
quantised to 1/256 as texture hardware does (8-bit fractions), so exact cases stay exact: a tap
whose weight rounds to 0 is neither marked nor read.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from jaxrender.fusion import sum_small
from jaxrender.pipelines.os_sheet import CHUNK, LANES, ShadeSheet
from jaxrender.types import Array

CHUNK_BITS = CHUNK.bit_length() - 1  # CHUNK is a power of two

FRACTION = 256.0  # 8-bit LOD and bilinear fractions


class Taps(NamedTuple):
    """Per pixel P and tap K: virtual chunk int32[P, K], lane int32[P, K], weight float32[P, K]
    (0 for empty pixels and unused taps); lod float32[P] (selected, biased; -1 empty)."""

    chunk: Array
    lane: Array
    weight: Array
    lod: Array


class Footprint(NamedTuple):
    """Per pixel: object int32[P], chart point st float32[P, 2], footprint axes in chart units
    dst_dx, dst_dy float32[P, 2], covered bool[P]."""

    obj: Array
    st: Array
    dst_dx: Array
    dst_dy: Array
    covered: Array


def footprint(scene, sheet: ShadeSheet, tri: Array, bary: Array, dbx: Array, dby: Array
              ) -> Footprint:
    """Chart coordinates of flat pixels from their triangle and barycentrics (and derivatives)."""
    covered = tri >= 0
    t = jnp.maximum(tri, 0)
    c = sheet.corner_st[t]  # [P, 3, 2]
    st = sum_small(bary[:, :, None] * c, axis=1)
    dx = sum_small(dbx[:, :, None] * c, axis=1)
    dy = sum_small(dby[:, :, None] * c, axis=1)
    return Footprint(scene.tri_object[t], st, dx, dy, covered)


def _q(x: Array) -> Array:
    return jnp.round(x * FRACTION) / FRACTION


def raw_lod(fp: Footprint, sheet: ShadeSheet, aniso_taps: int):
    """Unbiased, unclamped LOD float32[P] in the object's level-0 shadels, the major footprint
    axis float32[P, 2] (chart units) and the top level float32[P] of each pixel's object."""
    res = sheet.obj_res[fp.obj]
    rf = res.astype(jnp.float32)
    lx = jnp.sqrt(sum_small(jnp.square(fp.dst_dx))) * rf
    ly = jnp.sqrt(sum_small(jnp.square(fp.dst_dy))) * rf
    major, minor = jnp.maximum(lx, ly), jnp.minimum(lx, ly)
    n = int(aniso_taps)
    size = major if n == 1 else jnp.maximum(minor, major / n)
    lod = jnp.log2(jnp.maximum(size, 1e-20))
    axis = jnp.where((lx >= ly)[:, None], fp.dst_dx, fp.dst_dy)
    top = (sheet.obj_levels[fp.obj] - 1).astype(jnp.float32)
    return jnp.where(jnp.isfinite(lod), lod, 0.0), axis, top


def taps(fp: Footprint, sheet: ShadeSheet, bias: Array, mode: str, aniso_taps: int) -> Taps:
    """The filter taps of every pixel at MIP bias ``bias`` (float32 scalar, traced). mode:
    "trilinear" (two levels), "bilinear" (the nearest level) or "finest" (the finer of the two
    trilinear levels alone, to measure what the second level costs)."""
    res = sheet.obj_res[fp.obj]
    nl = sheet.obj_levels[fp.obj]
    n = int(aniso_taps)
    lod, axis, top = raw_lod(fp, sheet, n)
    lod = jnp.clip(_q(lod + bias), 0.0, top)
    if mode == "trilinear":
        l0f = jnp.floor(lod)
        frac = lod - l0f
        l0 = l0f.astype(jnp.int32)
        levels = [(l0, 1.0 - frac), (jnp.minimum(l0 + 1, nl - 1), frac)]
    elif mode == "finest":
        levels = [(jnp.floor(lod).astype(jnp.int32), jnp.ones_like(lod))]
    else:
        levels = [(jnp.floor(lod + 0.5).astype(jnp.int32), jnp.ones_like(lod))]
    chunks, lanes, weights = [], [], []
    for lv, wl in levels:
        rl = jnp.right_shift(res, lv)
        rlf = rl.astype(jnp.float32)
        cps = rl >> CHUNK_BITS
        base = sheet.obj_base[fp.obj, lv]
        for i in range(n):
            off = (i + 0.5) / n - 0.5
            p = fp.st + axis * off if n > 1 else fp.st
            tx = p[:, 0] * rlf - 0.5
            ty = p[:, 1] * rlf - 0.5
            x0f, y0f = jnp.floor(tx), jnp.floor(ty)
            fx, fy = _q(tx - x0f), _q(ty - y0f)
            hi = (rl - 1).astype(jnp.float32)
            for dy, wy in ((0, 1.0 - fy), (1, fy)):
                for dx, wx in ((0, 1.0 - fx), (1, fx)):
                    x = jnp.clip(x0f + dx, 0.0, hi).astype(jnp.int32)
                    y = jnp.clip(y0f + dy, 0.0, hi).astype(jnp.int32)
                    # Shifts and masks are floor division and modulo by a power of two, without
                    # the sign corrections jnp's // and % add to each of a row's taps.
                    chunks.append(base + (y >> CHUNK_BITS) * cps + (x >> CHUNK_BITS))
                    lanes.append(((y & (CHUNK - 1)) << CHUNK_BITS) + (x & (CHUNK - 1)))
                    weights.append(wl * wx * wy / n)
    stack = lambda xs: jnp.stack(xs, axis=-1)
    w = jnp.where(fp.covered[:, None], stack(weights), 0.0)
    chunk = jnp.where(w > 0.0, stack(chunks), 0)
    lane = jnp.where(w > 0.0, stack(lanes), 0)
    return Taps(chunk, lane, w, jnp.where(fp.covered, lod, -1.0))


def _mark(idx: Array, n: int) -> Array:
    """bool[n]: True where some entry of idx points (out-of-range entries mark nothing).

    Every write stores the same int32 1, so which of several writes to one chunk lands does
    not matter, and the scatter needs no atomics. Many taps hit one chunk: on a GPU a bool
    scatter serialises on compare-and-swap loops for its bytes and an int32 max on atomics,
    both far slower than plain int32 stores."""
    return jnp.zeros((n,), jnp.int32).at[idx].set(1, mode="drop") > 0


def mark_chunks(t: Taps, n_chunks: int) -> Array:
    """bool[NC]: the virtual chunks some tap with non-zero weight reads."""
    return _mark(jnp.where(t.weight > 0.0, t.chunk, n_chunks).reshape(-1), n_chunks)


def mark_slot_shadels(t: Taps, page: Array, capacity: int) -> Array:
    """bool[capacity * 64]: the shadels of the store's slots that some tap with non-zero weight
    reads (``page`` int32[NC]: each virtual chunk's slot, -1 for none; a tap of a chunk without
    a slot marks nothing). Without an allocation overflow it is ``mark_shadels`` restricted to
    the allocated chunks, at the store's size instead of the virtual sheet's."""
    n = capacity * CHUNK * CHUNK
    slot = page[jnp.maximum(t.chunk, 0)]
    addr = jnp.where((t.weight > 0.0) & (slot >= 0), slot * (CHUNK * CHUNK) + t.lane, n)
    return _mark(addr.reshape(-1), n)


def mark_shadels(t: Taps, n_chunks: int) -> Array:
    """bool[NC * 64]: the virtual shadels some tap with non-zero weight reads."""
    n = n_chunks * CHUNK * CHUNK
    return _mark(jnp.where(t.weight > 0.0, t.chunk * (CHUNK * CHUNK) + t.lane, n).reshape(-1), n)


def needed_shadels(sheet: ShadeSheet, t: Taps, page: Array, owned_slot: Array):
    """Object space's needed shadels of taps ``t`` (read by a tap of non-zero weight, and
    owned), given the store's ``page`` table and its slots' owned bits bool[cap, 64]:
    (needed bool[R, 64], owned bool[R, 64], row_of) over rows R of 64 shadels: the store's
    slots or the virtual sheet's chunks, whichever is fewer (thin's sheet at 1080p has 2.3 M
    chunks for a store of 194 k slots; a small scene's sheet is smaller than the store).
    ``row_of(flags, v)`` reads a per-row flag at virtual chunk ``v``. The two agree unless the
    store overflowed, and then the frame is flagged (counts["overflow"]): every chunk a tap
    reads is allocated."""
    cap, nc = owned_slot.shape[0], sheet.n_chunks
    if cap < nc:
        needed = mark_slot_shadels(t, page, cap).reshape(cap, LANES) & owned_slot

        def row_of(flags, v):
            slot = page[jnp.maximum(v, 0)]
            return (slot >= 0) & flags[jnp.maximum(slot, 0)]

        return needed, owned_slot, row_of
    owned = sheet.owner.reshape(nc, LANES) >= 0
    needed = mark_shadels(t, nc).reshape(nc, LANES) & owned
    return needed, owned, lambda flags, v: flags[v]
