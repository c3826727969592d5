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

from jaxrender.raster.coverage import EMPTY_KEY
from jaxrender.types import Array, VisBuffer


def resolve(
    zbuf: Array, clip: Array, faces: Array, width: int, height: int, offset_px: Array
) -> VisBuffer:
    """zbuf int64[H*W] -> VisBuffer. ``offset_px``: float32[2] sample offset inside the pixel."""
    empty = zbuf == EMPTY_KEY
    tri = jnp.where(empty, -1, (zbuf & 0xFFFFFFFF).astype(jnp.int32)).reshape(height, width)
    depth_bits = (zbuf >> 32).astype(jnp.int32)
    depth = jnp.where(empty, 1.0, jax.lax.bitcast_convert_type(depth_bits, jnp.float32))
    depth = depth.reshape(height, width)
    bary, ddx, ddy = barycentrics(tri, clip, faces, width, height, offset_px)
    return VisBuffer(tri_id=tri, depth=depth, bary=bary, dbary_dx=ddx, dbary_dy=ddy)


def barycentrics(tri: Array, clip: Array, faces: Array, width: int, height: int, offset_px: Array):
    """Perspective-correct barycentrics and d/dx, d/dy for int32[H, W] triangle ids."""
    covered = tri >= 0
    verts = clip[faces[jnp.maximum(tri, 0)]]  # [H, W, 3, 4]
    c = jnp.stack([verts[..., 0], verts[..., 1], verts[..., 3]], axis=-1)  # [H, W, 3, 3]
    rows = jnp.stack(
        [
            jnp.cross(c[..., 1, :], c[..., 2, :]),
            jnp.cross(c[..., 2, :], c[..., 0, :]),
            jnp.cross(c[..., 0, :], c[..., 1, :]),
        ],
        axis=-2,
    )  # [H, W, 3 (vertex), 3 (u, v, 1)]
    # Normalise each pixel's rows by their largest magnitude: the ratios are unchanged and
    # float32 stays far from overflow for any finite clip coordinates.
    scale = jnp.max(jnp.abs(rows), axis=(-2, -1), keepdims=True)
    rows = rows / jnp.where(scale > 0, scale, 1.0)
    px = jnp.arange(width, dtype=jnp.float32)[None, :] + offset_px[0]
    py = jnp.arange(height, dtype=jnp.float32)[:, None] + offset_px[1]
    u = jnp.broadcast_to(px * (2.0 / width) - 1.0, (height, width))
    v = jnp.broadcast_to(1.0 - py * (2.0 / height), (height, width))
    e = rows[..., 0] * u[..., None] + rows[..., 1] * v[..., None] + rows[..., 2]  # [H, W, 3]
    s = jnp.sum(e, axis=-1, keepdims=True)
    ok = covered[..., None] & (s != 0.0)
    s = jnp.where(ok, s, 1.0)
    b = e / s
    db_du = (rows[..., 0] - b * jnp.sum(rows[..., 0], axis=-1, keepdims=True)) / s
    db_dv = (rows[..., 1] - b * jnp.sum(rows[..., 1], axis=-1, keepdims=True)) / s
    # Clamp into the triangle: a pixel centre can fall a rounding error outside it.
    bc = jnp.clip(b, 0.0, 1.0)
    bc = bc / jnp.maximum(jnp.sum(bc, axis=-1, keepdims=True), 1e-30)
    zero = jnp.zeros_like(b)
    bary = jnp.where(ok, bc, jnp.where(covered[..., None], 1.0 / 3.0, zero))
    ddx = jnp.where(ok, db_du * (2.0 / width), zero)
    ddy = jnp.where(ok, db_dv * (-2.0 / height), zero)
    return bary, ddx, ddy
