"""Attribute interpolation: (triangle id, barycentrics, their screen derivatives) -> SurfacePoints."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.fusion import all_small
from jaxrender.scene.camera import Camera
from jaxrender.scene.scene import Scene
from jaxrender.shading.vec import components, cross3, dot, dot3, normalize3, stack
from jaxrender.types import Array, SurfacePoints


def _at_corners(attr: Array, corners: list) -> list:
    """Vertex attribute [V, C] at each corner's vertex int32[N]: per corner, C components."""
    return [components(attr[c]) for c in corners]


def _interp(w: tuple, rows: list) -> tuple:
    """Barycentric weights (w0, w1, w2) of float32[N] applied to ``_at_corners`` rows -> the
    interpolated attribute as C components of float32[N]."""
    return tuple(w[0] * a + w[1] * b + w[2] * c for a, b, c in zip(*rows))


@jax.named_scope("surface_points")
def surface_points(scene: Scene, camera: Camera, tri_id: Array, bary: Array, dbary_dx: Array,
                   dbary_dy: Array) -> SurfacePoints:
    """A flat batch of N points: tri_id int32[N] (-1 = none), bary/dbary_dx/dbary_dy float32[N, 3]
    (perspective-correct barycentrics and their derivatives per pixel right / down).

    Position, normal, uv and tangent are interpolated with ``bary``; uv derivatives follow by
    the chain rule, duv/dx = sum_i dbary_i/dx * uv_i. The geometric normal (of the triangle) and
    the interpolated normal are flipped together when the triangle is seen from behind. Invalid
    points (tri_id < 0 or non-finite barycentrics) come back with valid False and finite values.
    Computed on per-point components (``vec.components``), as the shader is.
    """
    tri_id = jnp.asarray(tri_id, jnp.int32)
    valid = (tri_id >= 0) & (tri_id < scene.faces.shape[0])
    valid = valid & all_small(jnp.isfinite(bary))
    vcol = valid[:, None]
    w = components(jnp.where(vcol, bary, jnp.float32(1.0 / 3.0)))
    w_dx = components(jnp.where(vcol & jnp.isfinite(dbary_dx), dbary_dx, 0.0))
    w_dy = components(jnp.where(vcol & jnp.isfinite(dbary_dy), dbary_dy, 0.0))
    t = jnp.where(valid, tri_id, 0)
    corners = list(components(scene.faces[t]))
    p = _at_corners(scene.positions, corners)
    pos = _interp(w, p)
    up = (jnp.float32(0.0), jnp.float32(0.0), jnp.float32(1.0))
    n_interp = _interp(w, _at_corners(scene.normals, corners))
    edge1 = tuple(b - a for a, b in zip(p[0], p[1]))
    edge2 = tuple(b - a for a, b in zip(p[0], p[2]))
    n_geo = normalize3(cross3(edge1, edge2), normalize3(n_interp, up))
    n_shade = normalize3(n_interp, n_geo)
    view = normalize3(tuple(e - q for e, q in zip(components(camera.eye), pos)), n_geo)
    sign = jnp.where(dot3(n_geo, view) < 0.0, jnp.float32(-1.0), jnp.float32(1.0))
    n_geo, n_shade = tuple(c * sign for c in n_geo), tuple(c * sign for c in n_shade)
    tangent = _interp(w, _at_corners(scene.tangents[:, :3], corners)) + (
        scene.tangents[corners[0], 3],)

    def kept(v: tuple, fallback: tuple) -> Array:  # the point's value, or fallback if invalid
        return stack(tuple(jnp.where(valid, c, f) for c, f in zip(v, fallback)))

    zero, one = jnp.float32(0.0), jnp.float32(1.0)
    uvs = _at_corners(scene.uvs, corners)
    return SurfacePoints(
        position=kept(pos, (zero, zero, zero)),
        normal=kept(n_geo, up),
        shading_normal=kept(n_shade, up),
        tangent=kept(tangent, (one, zero, zero, one)),
        uv=stack(tuple(c * valid.astype(jnp.float32) for c in _interp(w, uvs))),
        duv_dx=stack(_interp(w_dx, uvs)),
        duv_dy=stack(_interp(w_dy, uvs)),
        view=kept(view, up),
        material=jnp.where(valid, scene.tri_material[t], 0),
        tri_id=jnp.where(valid, tri_id, -1),
        valid=valid,
    )


def view_depth(points: SurfacePoints, camera: Camera) -> Array:
    """float32[N]: each point's distance in front of the camera, along its forward axis."""
    return dot(points.position - camera.eye[None, :], camera.forward[None, :])[:, 0]
