"""Attribute interpolation: (triangle id, barycentrics, their screen derivatives) -> SurfacePoints."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.fusion import all_small, sum_small
from jaxrender.scene.camera import Camera
from jaxrender.scene.scene import Scene
from jaxrender.shading.vec import cross, dot, safe_normalize
from jaxrender.types import Array, SurfacePoints


def _interp(w: Array, attr: Array) -> Array:
    """w float32[N, 3], attr [N, 3, C] -> [N, C]."""
    return sum_small(w[:, :, None] * attr, axis=1)


@jax.named_scope("surface_points")
def surface_points(scene: Scene, camera: Camera, tri_id: Array, bary: Array, dbary_dx: Array,
                   dbary_dy: Array) -> SurfacePoints:
    """A flat batch of N points: tri_id int32[N] (-1 = none), bary/dbary_dx/dbary_dy float32[N, 3]
    (perspective-correct barycentrics and their derivatives per pixel right / down).

    Position, normal, uv and tangent are interpolated with ``bary``; uv derivatives follow by
    the chain rule, duv/dx = sum_i dbary_i/dx * uv_i. The geometric normal (of the triangle) and
    the interpolated normal are flipped together when the triangle is seen from behind. Invalid
    points (tri_id < 0 or non-finite barycentrics) come back with valid False and finite values.
    """
    tri_id = jnp.asarray(tri_id, jnp.int32)
    valid = (tri_id >= 0) & (tri_id < scene.faces.shape[0])
    valid = valid & all_small(jnp.isfinite(bary))
    vcol = valid[:, None]
    bary = jnp.where(vcol, bary, jnp.float32(1.0 / 3.0))
    dbary_dx = jnp.where(vcol & jnp.isfinite(dbary_dx), dbary_dx, 0.0)
    dbary_dy = jnp.where(vcol & jnp.isfinite(dbary_dy), dbary_dy, 0.0)
    t = jnp.where(valid, tri_id, 0)
    f = scene.faces[t]  # [N, 3]
    p = scene.positions[f]  # [N, 3, 3]
    pos = _interp(bary, p)
    z = jnp.zeros_like(pos)
    up = z + jnp.asarray([0.0, 0.0, 1.0], jnp.float32)[None, :]
    n_interp = _interp(bary, scene.normals[f])
    n_geo = safe_normalize(cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), safe_normalize(n_interp, up))
    n_shade = safe_normalize(n_interp, n_geo)
    view = safe_normalize(camera.eye[None, :] - pos, n_geo)
    flip = dot(n_geo, view) < 0.0
    sign = jnp.where(flip, jnp.float32(-1.0), jnp.float32(1.0))
    n_geo, n_shade = n_geo * sign, n_shade * sign
    tan_v = scene.tangents[f]
    tangent = jnp.concatenate([_interp(bary, tan_v[:, :, :3]), tan_v[:, 0, 3:4]], axis=-1)
    uv_v = scene.uvs[f]
    return SurfacePoints(
        position=jnp.where(vcol, pos, 0.0),
        normal=jnp.where(vcol, n_geo, up),
        shading_normal=jnp.where(vcol, n_shade, up),
        tangent=jnp.where(vcol, tangent, jnp.asarray([1.0, 0.0, 0.0, 1.0], jnp.float32)[None, :]),
        uv=_interp(bary, uv_v) * vcol.astype(jnp.float32),
        duv_dx=_interp(dbary_dx, uv_v),
        duv_dy=_interp(dbary_dy, uv_v),
        view=jnp.where(vcol, view, up),
        material=jnp.where(valid, scene.tri_material[t], 0),
        tri_id=jnp.where(valid, tri_id, -1),
        valid=valid,
    )


def view_depth(points: SurfacePoints, camera: Camera) -> Array:
    """float32[N]: each point's distance in front of the camera, along its forward axis."""
    return dot(points.position - camera.eye[None, :], camera.forward[None, :])[:, 0]
