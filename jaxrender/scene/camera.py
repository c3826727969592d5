"""Pinhole cameras with GL conventions (right-handed, looking down -Z, NDC y up).

A camera is a pytree of arrays, so moving it never recompiles a jitted renderer. Vertices are
transformed camera-relative (``p - eye`` first, then a rotation), never through a 4x4 matrix
that carries the translation: with world coordinates 1e5 from the origin a float32 matrix
product would round the translation into the result. All products are elementwise, so no
reduced-precision matrix unit (TF32 on a GPU) touches geometry.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxrender.types import Array, pytree_dataclass


@pytree_dataclass
class Camera:
    """eye float32[3]; rotation float32[3, 3] world -> camera (rows: right, up, backward);
    fov_y float32[] vertical field of view in radians; near, far float32[] clip distances;
    jitter float32[2] or None: a sub-pixel offset of the projection in NDC units (x right, y
    up), as TAA shifts it; None (the default) compiles no offset."""

    eye: Array
    rotation: Array
    fov_y: Array
    near: Array
    far: Array
    jitter: Array | None = None

    @property
    def forward(self) -> Array:
        return -self.rotation[..., 2, :]


def look_at(eye, target, up=(0.0, 1.0, 0.0), *, fov_y_deg=60.0, near=0.1, far=100.0) -> Camera:
    """A camera at ``eye`` looking at ``target``. Raises ValueError for a degenerate set-up."""
    eye_np = np.asarray(eye, np.float64)
    fwd = np.asarray(target, np.float64) - eye_np
    if not np.all(np.isfinite(fwd)) or np.linalg.norm(fwd) == 0.0:
        raise ValueError(f"look_at: eye {eye} and target {target} must differ and be finite")
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(up, np.float64))
    if np.linalg.norm(right) < 1e-12:
        raise ValueError(f"look_at: up {up} is parallel to the view direction")
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    if not (0.0 < fov_y_deg < 180.0):
        raise ValueError(f"look_at: fov_y_deg must be in (0, 180), got {fov_y_deg}")
    if not (0.0 < near < far):
        raise ValueError(f"look_at: need 0 < near < far, got near={near}, far={far}")
    rotation = np.stack([right, true_up, -fwd])
    return Camera(
        eye=jnp.asarray(eye_np, jnp.float32),
        rotation=jnp.asarray(rotation, jnp.float32),
        fov_y=jnp.float32(np.deg2rad(fov_y_deg)),
        near=jnp.float32(near),
        far=jnp.float32(far),
    )


def world_to_view(points: Array, camera: Camera) -> Array:
    """float32[..., 3] world positions -> camera space (camera at the origin, looking down -Z)."""
    lead = (1,) * (points.ndim - 1)  # explicit broadcasting (rank promotion may be "raise")
    d = points - camera.eye.reshape(lead + (3,))
    return jnp.sum(d[..., None, :] * camera.rotation.reshape(lead + (3, 3)), axis=-1)


def view_to_clip(view: Array, camera: Camera, aspect: float) -> Array:
    """GL perspective projection of camera-space points, elementwise: float32[..., 4]."""
    f = 1.0 / jnp.tan(camera.fov_y * 0.5)
    n, fa = camera.near, camera.far
    x, y, z = view[..., 0], view[..., 1], view[..., 2]
    zc = (fa + n) / (n - fa) * z + (2.0 * fa * n) / (n - fa)
    xc, yc = f / aspect * x, f * y
    if camera.jitter is not None:  # x_ndc + jx = (xc + jx * w) / w, with w = -z
        xc, yc = xc - camera.jitter[..., 0] * z, yc - camera.jitter[..., 1] * z
    return jnp.stack([xc, yc, zc, -z], axis=-1)


def without_jitter(camera: Camera) -> Camera:
    return dataclasses.replace(camera, jitter=None) if camera.jitter is not None else camera


def with_jitter_px(camera: Camera, offset_px: Array, width: int, height: int) -> Camera:
    """The camera with its projection shifted by ``offset_px`` (x right, y down, pixels)."""
    ndc = jnp.stack([2.0 * offset_px[0] / width, -2.0 * offset_px[1] / height])
    return dataclasses.replace(camera, jitter=ndc.astype(jnp.float32))


def world_to_clip(points: Array, camera: Camera, aspect: float) -> Array:
    return view_to_clip(world_to_view(points, camera), camera, aspect)
