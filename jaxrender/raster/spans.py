"""CPU traversal: exact per-row spans instead of bounding boxes.

The bounding-box traversal (``coverage.py``) makes every box pixel a work item and tests it;
on the 640x360 terrain that is 460k items for 141k fragments, and on a CPU every item pays for
~20 gathers, the edge tests and the scatter. Here each triangle's box is first expanded into
rows; each row solves its three edge inequalities for the exact run of covered pixels, and only
those pixels become items, so items = fragments and no item needs a coverage test. The row
stage costs one item per box row (45k on the terrain).

Exactness: with F = B sy + C + A ox, a pixel x of the row is covered by edge i iff
``256 A x + F + tl > 0`` (the same integer as ``E(P) + tl`` in ``coverage.py``, every term
exact in float64). The bound is first estimated by a float64 division, whose floor/ceil can be
off by one, then corrected by evaluating the exact inequality at its neighbours. Items carry the
same exact edge values as the box traversal, so depths, and the whole VisBuffer, are identical
(``tests/raster/test_spans.py``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.raster.work_items import WorkChunk, owners, window_depth
from jaxrender.raster.setup import SUBPIXEL, TriSetup
from jaxrender.types import Array

_FAR = 1 << 30  # a column bound beyond any image (width < 2^31, boxes inside the image)


def span_capacities(capacity: int) -> tuple[int, int]:
    """(rows, pixels) per chunk from the box traversal's item capacity. Rows are ~1/10 of the
    box pixels and covered pixels ~1/3 (640x360 terrain: 45k rows, 141k fragments, 460k box
    pixels); a chunk costs its full size, so the default runs one row chunk there, and the
    pixels as one chunk plus one quarter chunk (see ``_in_chunks``)."""
    return max(capacity // 8, 64), max(capacity // 4, 64)


def _cumsum(x: Array) -> Array:
    # jnp.cumsum is a reduce-window on XLA CPU, several times slower than the associative
    # scan.
    return jax.lax.associative_scan(jnp.add, x)


def _row_bounds(a: Array, g: Array, lo: Array, hi: Array) -> tuple[Array, Array]:
    """Integer x in [lo, hi] (int32) with a x + g > 0 (a, g: exact integers in float64), as a
    closed range (first, last); empty when first > last."""
    pos = a > 0
    q = -g / jnp.where(a == 0, 1.0, a)  # the crossing: x > q where a > 0, x < q where a < 0
    # The bound nearest the crossing: floor(q) + 1 (a > 0) or ceil(q) - 1 (a < 0), off by at
    # most one (q can round onto an integer). Clamped to just outside [lo, hi] so that every
    # value stays small and exact, then corrected by the exact inequality at its neighbours:
    # ``out`` steps away from the covered side.
    b = jnp.where(pos, jnp.floor(q) + 1.0, jnp.ceil(q) - 1.0)
    b = jnp.clip(b, lo.astype(jnp.float64) - 2.0, hi.astype(jnp.float64) + 2.0)
    out = jnp.where(pos, -1.0, 1.0)
    b = jnp.where(a * (b + out) + g > 0, b + out, jnp.where(a * b + g > 0, b, b - out))
    b = b.astype(jnp.int32)
    # a == 0: the whole row or nothing.
    flat = jnp.where(g > 0, -_FAR, _FAR)
    first = jnp.where(pos, b, jnp.where(a < 0, -_FAR, flat))
    last = jnp.where(a < 0, b, jnp.where(pos, _FAR, -flat))
    return first, last


def _rows(setup: TriSetup, incl: Array, base: Array, capacity: int, offset: Array) -> dict:
    """Row items [base, base + capacity) -> per-row table (arrays of shape [capacity])."""
    slot, r, live = owners(setup.bh, incl, base, capacity)
    ox, oy = offset[0].astype(jnp.float64), offset[1].astype(jnp.float64)
    y = setup.y0[slot] + r
    sy = (y * SUBPIXEL).astype(jnp.float64) + oy
    x0 = setup.x0[slot]
    first, last = x0, x0 + setup.bw[slot] - 1
    ea, eb, ec = setup.edge_a[slot], setup.edge_b[slot], setup.edge_c[slot]
    tl, z = setup.top_left[slot], setup.z[slot]
    row = {}
    for i in range(3):
        a = ea[:, i]
        f = eb[:, i] * sy + ec[:, i] + a * ox  # E at the row's column 0, as an exact integer
        a = a * SUBPIXEL
        lo, hi = _row_bounds(a, f + tl[:, i], x0, x0 + setup.bw[slot] - 1)
        first, last = jnp.maximum(first, lo), jnp.minimum(last, hi)
        row[f"a{i}"], row[f"f{i}"], row[f"z{i}"] = a, f, z[:, i]
    row["n"] = jnp.where(live, jnp.maximum(last - first + 1, 0), 0)
    row.update(x=first, y=y, slot=slot, tri=setup.tri[slot], inv_area=setup.inv_area[slot])
    return row


def _pixels(row: dict, incl: Array, base: Array, capacity: int) -> WorkChunk:
    r, k, live = owners(row["n"], incl, base, capacity)
    g = {key: v[r] for key, v in row.items() if key != "n"}
    px = g["x"] + k
    xf = px.astype(jnp.float64)
    e = [g[f"a{i}"] * xf + g[f"f{i}"] for i in range(3)]  # = E(P) of the box traversal
    depth = window_depth(e, [g[f"z{i}"] for i in range(3)], g["inv_area"])
    return WorkChunk(g["slot"], g["tri"], px, g["y"], live, depth)


def _computed_once(make, true: Array):
    """``make()``, computed into buffers of its own. XLA CPU otherwise fuses the row-bound
    arithmetic into every level of the scan below and every gather of the pixel stage, and
    re-evaluates it there (a fifth of the frame on a 2-core CPU).
    ``optimization_barrier`` does not stop it (the CPU pipeline removes barriers before
    fusion); a conditional's results are always buffers. ``true`` is a traced predicate that
    holds, so that the conditional is not folded away; computing inside the branch writes the
    table once, where passing it through the branch would copy it."""
    shapes = jax.eval_shape(make)
    zeros = lambda: jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)
    return jax.lax.cond(true, make, zeros)


def _in_chunks(total: Array, cap: int, state, body):
    """``state = body(state, base, size)`` over the items [0, total): full chunks of ``cap``,
    then the rest in chunks of cap / 4. A chunk costs its full size, so this bounds the
    waste of the last chunk by cap / 4 instead of cap (the 640x360 terrain's 141k pixels
    run as 131k + 33k instead of 2 x 131k)."""
    small = max(cap // 4, 1)
    n_big = total // cap
    state = jax.lax.fori_loop(jnp.int64(0), n_big, lambda k, st: body(st, k * cap, cap), state)
    done = n_big * cap
    n_small = (total - done + small - 1) // small
    return jax.lax.fori_loop(
        jnp.int64(0), n_small, lambda k, st: body(st, done + k * small, small), state
    )


def for_each_span_chunk(setup: TriSetup, capacity: int, offset: Array, state, fn):
    """``coverage.for_each_chunk`` by spans: rows in chunks, then each row chunk's covered
    pixels in chunks (both loops have dynamic trip counts; nothing is dropped)."""
    row_cap, pix_cap = span_capacities(capacity)
    rows_incl = jnp.cumsum(setup.bh.astype(jnp.int64))  # over triangles: small

    def row_chunk(st, base, cap):
        row = _computed_once(lambda: _rows(setup, rows_incl, base, cap, offset),
                             base < rows_incl[-1])
        incl = _cumsum(row["n"].astype(jnp.int64))
        return _in_chunks(incl[-1], pix_cap, st,
                          lambda st2, b, c: fn(st2, _pixels(row, incl, b, c)))

    # Rows run in equal chunks: splitting their last chunk too would split the pixel work
    # into more, smaller runs (measured: no gain).
    n_row_chunks = (rows_incl[-1] + row_cap - 1) // row_cap
    return jax.lax.fori_loop(jnp.int64(0), n_row_chunks,
                             lambda i, st: row_chunk(st, i * row_cap, row_cap), state)
