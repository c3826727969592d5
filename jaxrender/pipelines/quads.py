"""Sorted-stream helpers for replaying draws: segmented scans and 2x2 quad grouping.

Pixel shaders run in 2x2 quads: a quad of a triangle with k pixels to shade launches 4 lanes,
4 - k of them helper lanes. Quads here are read off the list of (triangle, pixel) units that a
pass shades, never estimated.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.raster.work_items import running_max
from jaxrender.sorting import EMPTY, lex_sort, lex_sort_prefix
from jaxrender.types import Array

BIG = EMPTY  # the key of an unused entry: sorts last


def segment_starts(*keys: Array) -> Array:
    """bool[N]: True where any key differs from the previous entry (and at entry 0)."""
    n = keys[0].shape[0]
    start = jnp.zeros((n,), bool).at[0].set(True)
    for k in keys:
        start = start | jnp.concatenate([jnp.ones((1,), bool), k[1:] != k[:-1]])
    return start


def segmented_cummin(values: Array, start: Array) -> Array:
    """Inclusive running minimum of float32[N] (or of each column of float32[N, K]) restarting
    where ``start`` bool[N] is True: a packed-key
    cummin on a GPU (a reduce-window there, about ten times faster than the scan over (flag,
    value) pairs at 8M entries), the associative scan on a CPU (where a reduce-window is
    slower). The choice is made when the program is lowered for a platform."""
    return jax.lax.platform_dependent(values, start, cpu=scan_segmented_cummin,
                                      default=packed_segmented_cummin)


def scan_segmented_cummin(values: Array, start: Array) -> Array:
    """``segmented_cummin`` as an associative scan over (segment start, value) pairs."""

    def comb(a, b):
        fa, va = a
        fb, vb = b
        return fa | fb, jnp.where(fb, vb, jnp.minimum(va, vb))

    flags = start.reshape((-1,) + (1,) * (values.ndim - 1))
    _, out = jax.lax.associative_scan(comb, (flags, values))
    return out


def packed_segmented_cummin(values: Array, start: Array) -> Array:
    """``segmented_cummin`` as one plain running minimum of int64 keys: the high 32 bits count
    the segments down (a later segment's keys are below every earlier one's, so the minimum
    restarts), the low 32 bits are the float's bits in an order-preserving encoding. Exact for
    every non-NaN float32."""
    with jax.enable_x64(True):
        n = values.shape[0]
        bits = jax.lax.bitcast_convert_type(values.astype(jnp.float32), jnp.int32)
        ordered = jnp.where(bits >= 0, bits, bits ^ 0x7FFFFFFF).astype(jnp.int64) + (1 << 31)
        segment = jnp.cumsum(start, dtype=jnp.int64) - 1
        segment = segment.reshape((-1,) + (1,) * (values.ndim - 1))
        key = jax.lax.cummin(((n - segment) << 32) | ordered, axis=0)
        low = ((key & 0xFFFFFFFF) - (1 << 31)).astype(jnp.int32)
        back = jnp.where(low >= 0, low, low ^ 0x7FFFFFFF)
        return jax.lax.bitcast_convert_type(back, jnp.float32)


def exclusive_segmented_cummin(values: Array, start: Array) -> Array:
    """Minimum of the earlier entries of the same segment (+inf for a segment's first);
    values float32[N] or float32[N, K] (K columns, one segmentation)."""
    incl = segmented_cummin(values, start)
    prev = jnp.concatenate([jnp.full((1,) + values.shape[1:], jnp.inf, values.dtype), incl[:-1]])
    return jnp.where(start.reshape((-1,) + (1,) * (values.ndim - 1)), jnp.inf, prev)


def exclusive_lane_cummin(values: Array, start: Array, lane: Array) -> Array:
    """Minimum of the earlier entries of the same segment and the same lane (0..3): the
    per-pixel running minimum of a list grouped by 2x2 quad (``start``) whose pixels'
    entries interleave inside their quad; one scan of four columns."""
    lanes = jnp.arange(4, dtype=lane.dtype)
    cols = jnp.where(lane[:, None] == lanes[None, :], values[:, None], jnp.inf)
    excl = exclusive_segmented_cummin(cols, start)
    return jnp.take_along_axis(excl, jnp.clip(lane, 0, 3)[:, None], axis=1)[:, 0]


def first_of_segment_index(start: Array) -> Array:
    """int32[N]: index of the first entry of each entry's segment."""
    idx = jnp.arange(start.shape[0], dtype=jnp.int32)
    return running_max(jnp.where(start, idx, 0))


def quad_keys(pixel: Array, width: int) -> tuple[Array, Array]:
    """(quad index int32[N] on the grid of 2x2 quads, lane 0..3 inside the quad)."""
    x, y = pixel % width, pixel // width
    qw = (width + 1) // 2
    return (y // 2) * qw + x // 2, (y % 2) * 2 + x % 2


def first_units_of_quads(tri: Array, quad_start: Array, shaded: Array) -> Array:
    """bool[N]: the first shaded unit of each (triangle, quad) of a list ordered by quad, then
    triangle (``quad_start``: True at each quad's first entry): a quad's units of one triangle
    lie together there, so the quads are counted without sorting the units again."""
    group = quad_start | jnp.concatenate([jnp.ones((1,), bool), tri[1:] != tri[:-1]])
    before = jnp.cumsum(shaded, dtype=jnp.int32) - shaded.astype(jnp.int32)  # shaded before
    return shaded & (before == before[first_of_segment_index(group)])


def quad_list(tri: Array, pixel: Array, shaded: Array, width: int, height: int, n_tris: int,
              live: Array | None = None):
    """Group the shaded (triangle, pixel) units into 2x2 quads; with ``live`` (int32, traced),
    no unit at or past index ``live`` is shaded, and only the units before it are sorted.

    Returns a dict with ``order`` (unit indices sorted by triangle, quad, lane; unshaded last),
    ``tri``, ``quad``, ``lane`` in that order, ``start`` (bool: first unit of a quad),
    ``n_quads`` and ``quad_start`` (int32[N]: sorted position of the first unit of quad q for
    q < n_quads).
    """
    quad, lane = quad_keys(pixel, width)
    n = tri.shape[0]
    t = jnp.where(shaded, tri, BIG)
    q = jnp.where(shaded, quad, BIG)
    idx = jnp.arange(n, dtype=jnp.int32)
    n_quads_max = ((width + 1) // 2) * ((height + 1) // 2)
    keys = (t, q, jnp.where(shaded, lane, BIG))
    limits = (n_tris - 1, n_quads_max - 1, 3)
    if live is None:
        (t_s, q_s, l_s), (order,) = lex_sort(keys, limits, (idx,))
    else:
        n_live = jnp.minimum(live, n)
        (t_s, q_s, l_s), (order,) = lex_sort_prefix(keys, limits, (idx,), n_live)
    live = t_s != BIG
    start = segment_starts(t_s, q_s) & live
    n_quads = jnp.sum(start, dtype=jnp.int32)
    quad_start, _ = compact_indices(start, n)
    return {"order": order, "tri": t_s, "quad": q_s, "lane": l_s, "start": start,
            "live": live, "n_quads": n_quads, "quad_start": quad_start}
