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
    """Perspective-correct barycentrics and d/dx, d/dy for int32[H, W] triangle ids.

    Written as explicit scalar algebra on the nine gathered (x, y, w) values so that XLA fuses
    the whole resolve into one pass over the pixels.
    """
    covered = tri >= 0
    verts = clip[faces[jnp.maximum(tri, 0)]]  # [H, W, 3, 4]
    x = [verts[..., i, 0] for i in range(3)]
    y = [verts[..., i, 1] for i in range(3)]
    w = [verts[..., i, 3] for i in range(3)]
    px = jnp.arange(width, dtype=jnp.float32)[None, :] + offset_px[0]
    py = jnp.arange(height, dtype=jnp.float32)[:, None] + offset_px[1]
    u = jnp.broadcast_to(px * (2.0 / width) - 1.0, (height, width))
    v = jnp.broadcast_to(1.0 - py * (2.0 / height), (height, width))
    # Rows of the adjugate: row_i = c_j x c_k for (i, j, k) cyclic, c = (x, y, w).
    ru, rv, r1, e = [], [], [], []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        a = y[j] * w[k] - w[j] * y[k]
        b = w[j] * x[k] - x[j] * w[k]
        c = x[j] * y[k] - y[j] * x[k]
        ru.append(a)
        rv.append(b)
        r1.append(c)
        e.append(a * u + b * v + c)
    s = e[0] + e[1] + e[2]
    ok = covered & (s != 0.0) & jnp.isfinite(s)
    s = jnp.where(ok, s, 1.0)
    su, sv = ru[0] + ru[1] + ru[2], rv[0] + rv[1] + rv[2]
    b = [ei / s for ei in e]
    dbx = [(ru[i] - b[i] * su) / s * (2.0 / width) for i in range(3)]
    dby = [(rv[i] - b[i] * sv) / s * (-2.0 / height) for i in range(3)]
    # Clamp into the triangle: a pixel centre can fall a rounding error outside it.
    bc = [jnp.clip(bi, 0.0, 1.0) for bi in b]
    norm = jnp.maximum(bc[0] + bc[1] + bc[2], 1e-30)
    third = jnp.float32(1.0 / 3.0)
    bary = jnp.stack(
        [jnp.where(ok, bi / norm, jnp.where(covered, third, 0.0)) for bi in bc], axis=-1
    )
    ddx = jnp.stack([jnp.where(ok, d, 0.0) for d in dbx], axis=-1)
    ddy = jnp.stack([jnp.where(ok, d, 0.0) for d in dby], axis=-1)
    return bary, ddx, ddy
