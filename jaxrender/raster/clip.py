"""Clipping in homogeneous clip space, before the perspective divide.

Triangles are clipped against the near and far planes (so nothing behind the eye produces a
fragment, and a triangle crossing the near plane is clipped rather than dropped or exploded)
and against a guard band |x|, |y| <= G w that keeps snapped window coordinates inside the range
where integer edge functions are exact (see ``setup.py``). Sutherland-Hodgman on a fixed-size
polygon: a triangle clipped by 6 planes has at most 9 vertices, fanned into at most 7 triangles.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.types import Array

MAX_POLY = 9  # 3 vertices + at most one more per plane
MAX_FAN = MAX_POLY - 2


def planes(guard: float) -> np.ndarray:
    """The six clip planes as rows (a, b, c, d): a point is inside when a x + b y + c z + d w >= 0."""
    return np.array(
        [
            [0, 0, 1, 1],  # near:  z >= -w
            [0, 0, -1, 1],  # far:   z <=  w
            [-1, 0, 0, guard],  # x <= G w
            [1, 0, 0, guard],  # x >= -G w
            [0, -1, 0, guard],  # y <= G w
            [0, 1, 0, guard],  # y >= -G w
        ],
        np.float32,
    )


def _inside_each_plane(points: Array, guard: float) -> Array:
    """bool[..., 6]: d >= 0 for each plane, each distance written out from its two non-zero
    terms. The 4-term sum over ``planes`` rows is a reduction over a tiny axis: XLA CPU hands
    it to a library call and XLA GPU to a reduction kernel, both slow. Only signs are used here, and the terms with a zero coefficient are exact
    zeros, so the two forms agree except where a vertex lies within rounding of the guard band,
    100 screens away (the clipper then decides with its own arithmetic, which is unchanged)."""
    x, y, z, w = (points[..., i] for i in range(4))
    gw = jnp.float32(guard) * w
    d = [z + w, w - z, gw - x, x + gw, gw - y, y + gw]
    return jnp.stack([di >= 0.0 for di in d], axis=-1)


def classify(tri_clip: Array, guard: float) -> tuple[Array, Array]:
    """For float32[T, 3, 4]: (inside: all vertices inside every plane, crossing: needs clipping).

    A triangle with all three vertices outside one plane is rejected (neither flag set).
    """
    inside_v = _inside_each_plane(tri_clip, guard)  # [T, 3, 6]
    inside = jnp.all(inside_v, axis=(1, 2))
    rejected = jnp.any(jnp.all(~inside_v, axis=1), axis=1)
    return inside, ~inside & ~rejected


def _clip_against(poly: Array, n: Array, plane: Array) -> tuple[Array, Array]:
    """Clip a batch of convex polygons [B, MAX_POLY, 4] with n vertices against one plane."""
    idx = jnp.arange(MAX_POLY, dtype=jnp.int32)
    nxt = jnp.where(idx[None, :] + 1 < n[:, None], idx[None, :] + 1, 0)  # [B, MAX_POLY]
    a = poly
    b = jnp.take_along_axis(poly, nxt[..., None], axis=1)
    plane = plane[None, None, :]
    da = jnp.sum(a * plane, axis=-1)
    db = jnp.sum(b * plane, axis=-1)
    live = idx[None, :] < n[:, None]
    a_in, b_in = da >= 0.0, db >= 0.0
    # The intersection is computed from the inside end towards the outside end, so that two
    # triangles sharing this edge (in either direction) compute bit-identical vertices.
    p_in = jnp.where(a_in[..., None], a, b)
    p_out = jnp.where(a_in[..., None], b, a)
    d_in = jnp.where(a_in, da, db)
    d_out = jnp.where(a_in, db, da)
    t = d_in / (d_in - d_out)
    hit = p_in + t[..., None] * (p_out - p_in)
    emit_a = live & a_in
    emit_hit = live & (a_in != b_in)
    cand = jnp.stack([a, hit], axis=2).reshape(poly.shape[0], 2 * MAX_POLY, 4)
    mask = jnp.stack([emit_a, emit_hit], axis=2).reshape(poly.shape[0], 2 * MAX_POLY)
    # Compact the emitted vertices to the front, in order (a prefix sum, no sort).
    pos = jnp.where(mask, jnp.cumsum(mask, axis=1) - 1, MAX_POLY)
    rows = jnp.broadcast_to(jnp.arange(poly.shape[0])[:, None], pos.shape)
    out = jnp.zeros_like(poly).at[rows, pos].set(cand, mode="drop")
    return out, jnp.minimum(jnp.sum(mask, axis=1), MAX_POLY).astype(jnp.int32)


def clip_triangles(tri_clip: Array, guard: float) -> tuple[Array, Array]:
    """float32[B, 3, 4] -> fan triangles float32[B, MAX_FAN, 3, 4] and their validity [B, MAX_FAN]."""
    bsz = tri_clip.shape[0]
    poly = jnp.zeros((bsz, MAX_POLY, 4), tri_clip.dtype).at[:, :3].set(tri_clip)
    n = jnp.full((bsz,), 3, jnp.int32)
    for plane in planes(guard):
        poly, n = _clip_against(poly, n, jnp.asarray(plane))
    k = jnp.arange(1, MAX_FAN + 1, dtype=jnp.int32)
    fan = jnp.stack(
        [
            jnp.broadcast_to(poly[:, :1], (bsz, MAX_FAN, 4)),
            poly[:, k],
            poly[:, jnp.minimum(k + 1, MAX_POLY - 1)],
        ],
        axis=2,
    )
    valid = k[None, :] + 1 < n[:, None]
    return fan, valid
