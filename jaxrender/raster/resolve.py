"""Resolve: from the winning (depth, id) key of each pixel to a VisBuffer with perspective-correct
barycentrics and their analytic screen-space derivatives.

Barycentrics come from 2D homogeneous rasterization (Olano and Greer 1997): with the triangle's
clip-space columns c_i = (x_i, y_i, w_i), the rows of adj([c0 c1 c2]) are c1 x c2, c2 x c0 and
c0 x c1, and for the NDC sample point p = (u, v, 1) the perspective-correct barycentrics are
e_i / sum(e) with e_i = row_i . p. This needs no clipped vertices, so a triangle with a vertex
behind the eye resolves exactly like any other, and the derivatives follow by the quotient rule.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.fusion import all_small, max_small, sum_small
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


def barycentrics_at(tri: Array, x: Array, y: Array, clip: Array, faces: Array, width: int,
                    height: int):
    """Perspective-correct barycentrics [..., 3] and their derivatives per pixel (right, down)
    at window points (x, y) (float32, any shape, pixel centres at +0.5) of valid triangles
    ``tri`` (int32, same shape). Clamped into the triangle and renormalised; where the point's
    homogeneous weights vanish the barycentrics are 1/3 and the derivatives 0. Returns
    (bary, d/dx, d/dy, ok).

    Written as explicit scalar algebra on the nine gathered (x, y, w) values so that XLA fuses
    it into one pass.
    """
    verts = clip[faces[tri]]  # [..., 3, 4]
    rows = adjugate_rows(verts)
    return _from_rows(rows, x, y, width, height)


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


def _from_rows(rows: list, x: Array, y: Array, width: int, height: int):
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
    bary = jnp.stack([jnp.where(ok, bi / norm, third) for bi in bc], axis=-1)
    ddx = jnp.stack(
        [jnp.where(ok, (ru[i] - b[i] * su) / s * (2.0 / width), 0.0) for i in range(3)], -1
    )
    ddy = jnp.stack(
        [jnp.where(ok, (rv[i] - b[i] * sv) / s * (-2.0 / height), 0.0) for i in range(3)], -1
    )
    return bary, ddx, ddy, ok


def barycentrics(tri: Array, clip: Array, faces: Array, width: int, height: int, offset_px: Array):
    """Barycentrics and d/dx, d/dy for int32[H, W] triangle ids (-1: empty, all zeros) at the
    sample point ``offset_px`` inside each pixel."""
    x = jnp.broadcast_to(jnp.arange(width, dtype=jnp.float32)[None, :] + offset_px[0],
                         (height, width))
    y = jnp.broadcast_to(jnp.arange(height, dtype=jnp.float32)[:, None] + offset_px[1],
                         (height, width))
    return barycentrics_from_rows(triangle_rows(clip, faces), tri, x, y, width, height)


def triangle_rows(clip: Array, faces: Array) -> list:
    """The nine adjugate entries of every triangle, as ``adjugate_rows`` gives them, each
    float32[T]: computed once, gathered per point by ``barycentrics_from_rows``."""
    return adjugate_rows(clip[faces])


def barycentrics_from_rows(rows: list, tri: Array, x: Array, y: Array, width: int,
                           height: int):
    """``barycentrics_at``'s barycentrics and d/dx, d/dy (zeros where ``tri`` is -1) at window
    points x, y (float32, ``tri``'s shape), from ``triangle_rows``'s entries.

    The entries are gathered per point as separate columns: on XLA CPU the per-point gather of
    3 x 4 vertex floats through ``faces`` is a materialised slice gather, slow. ``barycentrics``
    is this at every pixel; the reference calls it per shaded sample, so that its passes keep
    ids and depths only and a compacted launch computes the barycentrics of its samples alone.
    The three results are stacked [..., 3]. Returned as columns, XLA computes them again in
    every kernel that uses them instead of storing them: fewer bytes in the offline GPU
    program, but 1.3-10x slower on the CPU (``benchmarks/variants/barycentric_columns.patch``,
    RESULTS.md, forty-first session)."""
    covered = tri >= 0
    t = jnp.maximum(tri, 0)
    bary, ddx, ddy, _ = _from_rows([tuple(col[t] for col in r) for r in rows], x, y, width,
                                   height)
    c = covered[..., None]
    return jnp.where(c, bary, 0.0), jnp.where(c, ddx, 0.0), jnp.where(c, ddy, 0.0)


def pair_barycentrics(clip: Array, faces: Array, tri: Array, px: Array, py: Array,
                      width: int, height: int, offset=(0.5, 0.5)):
    """Perspective-correct barycentrics of triangle ``tri`` int32[N] at the sample point
    (px + ox, py + oy) of pixels px, py int32[N], and their d/dx, d/dy (per pixel right / down).

    The same homogeneous (Olano-Greer) formulation as ``barycentrics_at``, for a flat list of
    (triangle, pixel) pairs whose point may lie outside the triangle (quad helper lanes, chunk
    neighbours): there the barycentrics are extrapolated, unclamped, so the rows are scaled to
    a unit maximum first to keep the products in range. Returns three float32[N, 3].
    """
    verts = clip[faces[jnp.maximum(tri, 0)]]  # [N, 3, 4]
    c = jnp.stack([verts[..., 0], verts[..., 1], verts[..., 3]], axis=-1)  # [N, 3, 3]
    rows = jnp.stack([jnp.cross(c[:, 1], c[:, 2]), jnp.cross(c[:, 2], c[:, 0]),
                      jnp.cross(c[:, 0], c[:, 1])], axis=-2)
    scale = max_small(jnp.abs(rows), (-2, -1))
    rows = rows / jnp.where(scale > 0, scale, 1.0)
    u = (px.astype(jnp.float32) + offset[0]) * (2.0 / width) - 1.0
    v = 1.0 - (py.astype(jnp.float32) + offset[1]) * (2.0 / height)
    e = rows[..., 0] * u[:, None] + rows[..., 1] * v[:, None] + rows[..., 2]
    s = sum_small(e, keepdims=True)
    ok = (tri >= 0)[:, None] & (s != 0.0)
    s = jnp.where(ok, s, 1.0)
    b = e / s
    db_du = (rows[..., 0] - b * sum_small(rows[..., 0], keepdims=True)) / s
    db_dv = (rows[..., 1] - b * sum_small(rows[..., 1], keepdims=True)) / s
    inside = all_small(b >= 0.0)[:, None]
    # Inside the triangle clamp a rounding error away, as resolve does; outside extrapolate.
    bc = jnp.clip(b, 0.0, 1.0)
    bc = bc / jnp.maximum(sum_small(bc, keepdims=True), 1e-30)
    b = jnp.where(inside, bc, b)
    zero = jnp.zeros_like(b)
    third = jnp.full_like(b, 1.0 / 3.0)
    bary = jnp.where(ok, b, jnp.where((tri >= 0)[:, None], third, zero))
    ddx = jnp.where(ok, db_du * (2.0 / width), zero)
    ddy = jnp.where(ok, db_dv * (-2.0 / height), zero)
    return bary, ddx, ddy
