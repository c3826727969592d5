"""Triangle setup: snap to fixed point, exact integer edge functions, fill rule, pixel bounds.

Window coordinates are snapped to 1/256 pixel (8 sub-pixel bits) with float32 operations that
are each correctly rounded (divide, add, multiply by an exact constant, round half to even), so
every device and the NumPy reference snap identically. From there on every value is an
integer: edge functions ``E(P) = A Px + B Py + C`` are held in float64, which is exact here:
the guard band (see ``guard_band``) keeps |X|, |Y| below 2^24, so every product is below 2^50
and every sum below 2^52, integers that float64 represents exactly (and float64 arithmetic is
vectorised on CPUs, where int64 multiplication is not).

Conventions: pixel (px, py) has its centre at (px + 0.5, py + 0.5); y grows down the image
(row 0 is the top); a point exactly on an edge is covered only if that edge is a top edge
(horizontal, interior below) or a left edge (interior to its right): the D3D/GL top-left rule.
In these y-down coordinates a GL front face (counter-clockwise in NDC) has negative area.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp

from jaxrender.types import Array, pytree_dataclass

SUBPIXEL_BITS = 8
SUBPIXEL = 1 << SUBPIXEL_BITS
_COORD_BITS = 24  # |X|, |Y| < 2^24 after the guard band, so |E| < 2^52: exact in float64


def guard_band(width: int, height: int) -> float:
    """NDC half-extent G of the guard band: |x_ndc|, |y_ndc| <= G keeps |X| < 2^_COORD_BITS."""
    return float(2 ** (_COORD_BITS - SUBPIXEL_BITS)) / max(width, height) - 1.0


@pytree_dataclass
class TriSetup:
    """Per-triangle data the coverage loop gathers. Arrays have a leading triangle-slot axis."""

    edge_a: Array  # float64[N, 3] E_i(P) = A_i Px + B_i Py + C_i, edge i opposite vertex i,
    edge_b: Array  # float64[N, 3] oriented so that the interior is positive (integer values)
    edge_c: Array  # float64[N, 3]
    top_left: Array  # float64[N, 3] 1 where the edge is top or left (E == 0 counts as covered)
    z: Array  # float32[N, 3] window depth of the vertices
    inv_area: Array  # float32[N] 1 / (2 * area) in fixed-point units
    x0: Array  # int32[N] first pixel column of the bounding box (for these sample offsets)
    y0: Array  # int32[N]
    bw: Array  # int32[N] bounding box width in pixels (>= 1)
    bh: Array  # int32[N] bounding box height in rows; 0 for a slot that produces nothing
    count: Array  # int64[N] pixels in the bounding box; 0 for a slot that produces nothing
    tri: Array  # int32[N] id of the original triangle (a clipped fan keeps its parent's id)


def snap(tri_clip: Array, width: int, height: int) -> tuple[Array, Array, Array]:
    """float32[N, 3, 4] clip -> fixed-point X, Y (integer-valued float32[N, 3]: exact, since
    the guard band keeps |X|, |Y| below 2^24) and window depth float32[N, 3]."""
    w = tri_clip[..., 3]
    xs = jnp.round((tri_clip[..., 0] / w + 1.0) * jnp.float32(width * SUBPIXEL // 2))
    ys = jnp.round((1.0 - tri_clip[..., 1] / w) * jnp.float32(height * SUBPIXEL // 2))
    z = (tri_clip[..., 2] / w) * 0.5 + 0.5
    return xs, ys, z


def setup_triangles(
    tri_clip: Array,
    valid: Array,
    tri_ids: Array,
    width: int,
    height: int,
    offset: Array,
    cull_backfaces: bool,
) -> TriSetup:
    """Set up N triangle slots (float32[N, 3, 4] clip coordinates, all inside the guard band).

    ``offset`` is the sample position inside the pixel in fixed point, int64[2] (128, 128 for
    the centre), or int64[S, 2] for S samples tested per work item (the bounds then hold the
    pixels of every one). Must be called with 64-bit types enabled.
    """
    sx, sy, z = snap(tri_clip, width, height)
    return setup_snapped(sx, sy, z, valid, tri_ids, width, height, offset, cull_backfaces)


def setup_snapped(sx: Array, sy: Array, z: Array, valid: Array, tri_ids: Array, width: int,
                  height: int, offset: Array, cull_backfaces: bool) -> TriSetup:
    """``setup_triangles`` from snapped vertices (``snap``'s output): integer arithmetic only,
    exact in float64, so it gives the same bits wherever it runs (the GPU's traversal runs it
    per work item, see ``coverage.py``)."""
    sx, sy = sx.astype(jnp.float64), sy.astype(jnp.float64)
    area2 = (sx[:, 1] - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sy[:, 1] - sy[:, 0]) * (
        sx[:, 2] - sx[:, 0]
    )
    sign = jnp.where(area2 < 0, -1.0, 1.0)
    a_idx, b_idx = jnp.array([1, 2, 0]), jnp.array([2, 0, 1])
    xa, ya, xb, yb = sx[:, a_idx], sy[:, a_idx], sx[:, b_idx], sy[:, b_idx]
    dx = (xb - xa) * sign[:, None]
    dy = (yb - ya) * sign[:, None]
    edge_a, edge_b = -dy, dx
    edge_c = dy * xa - dx * ya
    top_left = ((dy < 0) | ((dy == 0) & (dx > 0))).astype(jnp.float64)

    # Pixels whose sample point (p * 256 + offset) can lie inside [min, max]; exact, since
    # dividing by a power of two is exact in floating point. With several offsets, the pixels
    # where any of them can (the union of their boxes).
    # Minima and maxima over the three vertices written out (exact either way): XLA CPU hands
    # a reduction over an axis of 3 to a library call, far slower than two elementwise ops.
    offs = [o.astype(jnp.float64) for o in offset.reshape(-1, 2)]
    ox_lo, oy_lo = functools.reduce(jnp.minimum, offs)
    ox_hi, oy_hi = functools.reduce(jnp.maximum, offs)
    lo = lambda v: jnp.minimum(jnp.minimum(v[:, 0], v[:, 1]), v[:, 2])
    hi = lambda v: jnp.maximum(jnp.maximum(v[:, 0], v[:, 1]), v[:, 2])
    x0 = jnp.maximum(jnp.ceil((lo(sx) - ox_hi) / SUBPIXEL), 0.0)
    x1 = jnp.minimum(jnp.floor((hi(sx) - ox_lo) / SUBPIXEL), width - 1.0)
    y0 = jnp.maximum(jnp.ceil((lo(sy) - oy_hi) / SUBPIXEL), 0.0)
    y1 = jnp.minimum(jnp.floor((hi(sy) - oy_lo) / SUBPIXEL), height - 1.0)
    bw = jnp.maximum(x1 - x0 + 1, 0.0).astype(jnp.int32)
    bh = jnp.maximum(y1 - y0 + 1, 0.0).astype(jnp.int32)
    keep = valid & (area2 != 0)
    if cull_backfaces:
        keep = keep & (area2 < 0)
    count = jnp.where(keep, bw.astype(jnp.int64) * bh.astype(jnp.int64), 0)
    inv_area = 1.0 / jnp.abs(area2).astype(jnp.float32)
    return TriSetup(
        edge_a=edge_a,
        edge_b=edge_b,
        edge_c=edge_c,
        top_left=top_left,
        z=z,
        inv_area=jnp.where(keep, inv_area, 0.0),
        x0=x0.astype(jnp.int32),
        y0=y0.astype(jnp.int32),
        bw=jnp.maximum(bw, 1),
        bh=jnp.where(count > 0, bh, 0),
        count=count,
        tri=tri_ids.astype(jnp.int32),
    )


class SetupFn:
    """Triangle setup for one frame size: ``setup(tri_clip, valid, ids, offset)`` (float32[n,
    3, 4], bool[n], int32[n], int64[2]) -> TriSetup, in two steps, ``snap(tri_clip)`` then
    ``from_snapped(sx, sy, z, valid, ids, offset)``."""

    def __init__(self, width: int, height: int, cull_backfaces: bool):
        self.width, self.height, self.cull = width, height, cull_backfaces

    def snap(self, tri_clip: Array):
        return snap(tri_clip, self.width, self.height)

    def from_snapped(self, sx, sy, z, valid, ids, offset) -> TriSetup:
        return setup_snapped(sx, sy, z, valid, ids, self.width, self.height, offset, self.cull)

    def __call__(self, tri_clip, valid, ids, offset) -> TriSetup:
        return self.from_snapped(*self.snap(tri_clip), valid, ids, offset)
