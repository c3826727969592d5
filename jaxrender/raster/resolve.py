"""Resolve: from the winning (depth, id) key of each pixel to a VisBuffer with perspective-correct
barycentrics and their analytic screen-space derivatives.

Barycentrics come from 2D homogeneous rasterization (Olano and Greer 1997): with the triangle's
clip-space columns c_i = (x_i, y_i, w_i), the rows of adj([c0 c1 c2]) are c1 x c2, c2 x c0 and
c0 x c1, and for the NDC sample point p = (u, v, 1) the perspective-correct barycentrics are
e_i / sum(e) with e_i = row_i . p. This needs no clipped vertices, so a triangle with a vertex
behind the eye resolves exactly like any other, and the derivatives follow by the quotient rule.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from jaxrender.raster.work_items import EMPTY_KEY
from jaxrender.types import Array, VisBuffer


def resolve(
    zbuf: Array, clip: Array, faces: Array, width: int, height: int, offset_px: Array
) -> VisBuffer:
    """zbuf int64[H*W] -> VisBuffer. ``offset_px``: float32[2] sample offset inside the pixel."""
    tri, depth = decode_keys(zbuf, width, height)
    bary, ddx, ddy = barycentrics(tri, clip, faces, width, height, offset_px)
    return VisBuffer(tri_id=tri, depth=depth, bary=bary, dbary_dx=ddx, dbary_dy=ddy)


def decode_keys(zbuf: Array, width: int, height: int) -> tuple[Array, Array]:
    """zbuf int64[H*W] of packed (depth, id) keys -> (tri_id int32[H, W], -1 where empty;
    depth float32[H, W], 1.0 where empty)."""
    # EMPTY_KEY compared half by half, in int32: the whole key compared would broadcast it at
    # the buffer's size, XLA would merge that with the buffer's initial fill, and the fill, now
    # read twice, would be copied before the depth test scatters into it.
    tri = (zbuf & 0xFFFFFFFF).astype(jnp.int32)  # -1 where empty: EMPTY_KEY's low half
    depth_bits = (zbuf >> 32).astype(jnp.int32)
    empty = (depth_bits == EMPTY_KEY >> 32) & (tri == -1)
    depth = jnp.where(empty, 1.0, jax.lax.bitcast_convert_type(depth_bits, jnp.float32))
    return tri.reshape(height, width), depth.reshape(height, width)


def adjugate_rows(verts: Array) -> list:
    """float32[..., 3, 4] clip-space vertices -> the nine adjugate entries [(a, b, c) per
    vertex], each float32[...]: row_i = c_j x c_k for (i, j, k) cyclic, c = (x, y, w)."""
    cx = [verts[..., i, 0] for i in range(3)]
    cy = [verts[..., i, 1] for i in range(3)]
    cw = [verts[..., i, 3] for i in range(3)]
    rows = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        rows.append((cy[j] * cw[k] - cw[j] * cy[k],
                     cw[j] * cx[k] - cx[j] * cw[k],
                     cx[j] * cy[k] - cy[j] * cx[k]))
    return rows


def _column_barycentrics(rows: list, x: Array, y: Array, width: int, height: int):
    """Perspective-correct barycentrics and their derivatives per pixel (right, down) at window
    points (x, y) (float32, any shape, pixel centres at +0.5), from the adjugate entries
    ``rows`` of each point's triangle: (bary, d/dx, d/dy), each a tuple of three columns.
    Clamped into the triangle and renormalised; where the point's homogeneous weights vanish
    the barycentrics are 1/3 and the derivatives 0. Explicit scalar algebra on the nine
    entries, so that XLA fuses it into one pass."""
    u = x * (2.0 / width) - 1.0
    v = 1.0 - y * (2.0 / height)
    ru = [r[0] for r in rows]
    rv = [r[1] for r in rows]
    e = [a * u + b * v + c for a, b, c in rows]
    s = e[0] + e[1] + e[2]
    ok = (s != 0.0) & jnp.isfinite(s)
    s = jnp.where(ok, s, 1.0)
    su, sv = ru[0] + ru[1] + ru[2], rv[0] + rv[1] + rv[2]
    b = [ei / s for ei in e]
    # Clamp into the triangle: a pixel centre can fall a rounding error outside it.
    bc = [jnp.clip(bi, 0.0, 1.0) for bi in b]
    norm = jnp.maximum(bc[0] + bc[1] + bc[2], 1e-30)
    third = jnp.float32(1.0 / 3.0)
    bary = tuple(jnp.where(ok, bi / norm, third) for bi in bc)
    ddx = tuple(jnp.where(ok, (ru[i] - b[i] * su) / s * (2.0 / width), 0.0) for i in range(3))
    ddy = tuple(jnp.where(ok, (rv[i] - b[i] * sv) / s * (-2.0 / height), 0.0) for i in range(3))
    return bary, ddx, ddy


def barycentrics(tri: Array, clip: Array, faces: Array, width: int, height: int, offset_px: Array):
    """Barycentrics and d/dx, d/dy for int32[H, W] triangle ids (-1: empty, all zeros) at the
    sample point ``offset_px`` inside each pixel."""
    x = jnp.broadcast_to(jnp.arange(width, dtype=jnp.float32)[None, :] + offset_px[0],
                         (height, width))
    y = jnp.broadcast_to(jnp.arange(height, dtype=jnp.float32)[:, None] + offset_px[1],
                         (height, width))
    columns = barycentrics_from_rows(triangle_rows(clip, faces), tri, x, y, width, height)
    return tuple(jnp.stack(v, axis=-1) for v in columns)


def triangle_rows(clip: Array, faces: Array) -> list:
    """The nine adjugate entries of every triangle, as ``adjugate_rows`` gives them, each
    float32[T]: computed once, gathered per point by ``barycentrics_from_rows``."""
    return adjugate_rows(clip[faces])


def barycentrics_from_rows(rows: list, tri: Array, x: Array, y: Array, width: int,
                           height: int):
    """Perspective-correct barycentrics and d/dx, d/dy (zeros where ``tri`` is -1) of triangles
    ``tri`` at window points x, y (float32, ``tri``'s shape), from ``triangle_rows``'s
    entries, each of the three as a tuple of its three columns (``surface.surface_points``
    takes them so).

    The entries are gathered per point as separate columns: on XLA CPU the per-point gather of
    3 x 4 vertex floats through ``faces`` is a materialised slice gather, slow. Left as
    columns, the values fuse into the kernels that use them: stacked, the [N, 3] arrays were
    stored between their computation and their use (the reference's passes, 1.2 GB at 1080p)."""
    covered = tri >= 0
    t = jnp.maximum(tri, 0)
    bary, ddx, ddy = _column_barycentrics([tuple(col[t] for col in r) for r in rows], x, y,
                                          width, height)
    return tuple(tuple(jnp.where(covered, c, 0.0) for c in v) for v in (bary, ddx, ddy))


def pair_barycentrics(clip: Array, faces: Array, tri: Array, px: Array, py: Array,
                      width: int, height: int, offset=(0.5, 0.5)):
    """``pair_barycentric_columns`` with each of its three results stacked: float32[N, 3]."""
    columns = pair_barycentric_columns(clip, faces, tri, px, py, width, height, offset)
    return tuple(jnp.stack(v, axis=-1) for v in columns)


def pair_barycentric_columns(clip: Array, faces: Array, tri: Array, px: Array, py: Array,
                             width: int, height: int, offset=(0.5, 0.5)):
    """Perspective-correct barycentrics of triangle ``tri`` int32[N] at the sample point
    (px + ox, py + oy) of pixels px, py int32[N], and their d/dx, d/dy (per pixel right / down),
    each as a tuple of three float32[N] columns (``surface.surface_points`` takes them so:
    left as columns they fuse into the kernels that use them, where stacked they were stored).

    The same homogeneous (Olano-Greer) formulation as ``barycentrics``, for a flat list of
    (triangle, pixel) pairs whose point may lie outside the triangle (quad helper lanes, chunk
    neighbours): there the barycentrics are extrapolated, unclamped, so the rows are scaled to
    a unit maximum first to keep the products in range.
    """
    rows = adjugate_rows(clip[faces[jnp.maximum(tri, 0)]])
    scale = functools.reduce(jnp.maximum, [jnp.abs(e) for row in rows for e in row])
    scale = jnp.where(scale > 0, scale, 1.0)
    rows = [tuple(e / scale for e in row) for row in rows]
    u = (px.astype(jnp.float32) + offset[0]) * (2.0 / width) - 1.0
    v = 1.0 - (py.astype(jnp.float32) + offset[1]) * (2.0 / height)
    e = [a * u + b * v + c for a, b, c in rows]
    s = e[0] + e[1] + e[2]
    covered = tri >= 0
    ok = covered & (s != 0.0)
    s = jnp.where(ok, s, 1.0)
    b = [ei / s for ei in e]
    su = rows[0][0] + rows[1][0] + rows[2][0]
    sv = rows[0][1] + rows[1][1] + rows[2][1]
    db_du = [(row[0] - bi * su) / s for row, bi in zip(rows, b)]
    db_dv = [(row[1] - bi * sv) / s for row, bi in zip(rows, b)]
    inside = (b[0] >= 0.0) & (b[1] >= 0.0) & (b[2] >= 0.0)
    # Inside the triangle clamp a rounding error away, as resolve does; outside extrapolate.
    bc = [jnp.clip(bi, 0.0, 1.0) for bi in b]
    norm = jnp.maximum(bc[0] + bc[1] + bc[2], 1e-30)
    b = [jnp.where(inside, ci / norm, bi) for ci, bi in zip(bc, b)]
    third = jnp.where(covered, jnp.float32(1.0 / 3.0), 0.0)
    return (tuple(jnp.where(ok, bi, third) for bi in b),
            tuple(jnp.where(ok, d * (2.0 / width), 0.0) for d in db_du),
            tuple(jnp.where(ok, d * (-2.0 / height), 0.0) for d in db_dv))
