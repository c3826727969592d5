"""Reprojection: where each pixel of frame t was in frame t-1, exactly, from the known camera
motion and the window depth of frame t (GL conventions: pixel centres at +0.5, row 0 at the
top, NDC y up, depth in [0, 1]). Camera math, used by temporal pipelines (checkerboard) and
the temporal metrics alike.
"""

from __future__ import annotations

import contextlib
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.scene.camera import Camera, view_to_clip
from jaxrender.types import Array

DEFAULT_DEPTH_TOLERANCE = 0.01  # relative difference of linear depth that counts as occlusion
FLOAT_DTYPES = (np.dtype(np.float32), np.dtype(np.float64))


class Reprojection(NamedTuple):
    """Where each pixel of frame t was in frame t-1.

    position: float[..., H, W, 2] window coordinates (x right, y down, pixel centres at +0.5).
    valid:    bool[..., H, W] on screen in t-1, in front of its camera, and (when the previous
              depth is known) not hidden there.
    depth:    float[..., H, W] the point's window depth in frame t-1.
    """

    position: Array
    valid: Array
    depth: Array



def cast_camera(cam: Camera, dtype) -> Camera:
    return jax.tree.map(lambda a: jnp.asarray(a).astype(dtype), cam)


def linear_depth(window_depth: Array, cam: Camera) -> Array:
    """Window depth in [0, 1] -> distance along the view axis (-z_view), inverse of GL's map."""
    n, f = cam.near, cam.far
    a = (f + n) / (n - f)
    b = (2.0 * f * n) / (n - f)
    return b / ((2.0 * window_depth - 1.0) + a)


def _view_to_world(v: Array, cam: Camera) -> Array:
    """Camera space (..., 3) -> world: eye + R^T v, with explicit elementwise products."""
    r = cam.rotation
    return jnp.stack(
        [cam.eye[j] + v[..., 0] * r[0, j] + v[..., 1] * r[1, j] + v[..., 2] * r[2, j]
         for j in range(3)], axis=-1)


def _world_to_view(p: Array, cam: Camera) -> Array:
    d = [p[..., j] - cam.eye[j] for j in range(3)]
    r = cam.rotation
    return jnp.stack([d[0] * r[i, 0] + d[1] * r[i, 1] + d[2] * r[i, 2] for i in range(3)],
                     axis=-1)


def _reproject_one(depth, cam, prev_cam, prev_depth, width, height, tol):
    dt = depth.dtype
    aspect = width / height
    x = jnp.arange(width, dtype=dt) + 0.5
    y = jnp.arange(height, dtype=dt) + 0.5
    xx = jnp.broadcast_to(x[None, :], (height, width))
    yy = jnp.broadcast_to(y[:, None], (height, width))
    x_ndc = 2.0 * xx / width - 1.0
    y_ndc = 1.0 - 2.0 * yy / height
    if cam.jitter is not None:  # the pixel centre saw the point the projection shifted there
        x_ndc, y_ndc = x_ndc - cam.jitter[0], y_ndc - cam.jitter[1]

    # Unproject frame t: view z from window depth, x and y from the pinhole.
    dist = linear_depth(depth, cam)  # = -z_view
    focal = 1.0 / jnp.tan(0.5 * cam.fov_y)
    view = jnp.stack([x_ndc * dist * aspect / focal, y_ndc * dist / focal, -dist], axis=-1)
    world = _view_to_world(view, cam)

    # Project into frame t-1 with the shared GL projection.
    clip = view_to_clip(_world_to_view(world, prev_cam), prev_cam, aspect)
    w = clip[..., 3]
    in_front = w > 0.0
    w_safe = jnp.where(in_front, w, 1.0)
    px = (clip[..., 0] / w_safe + 1.0) * (0.5 * width)
    py = (1.0 - clip[..., 1] / w_safe) * (0.5 * height)
    pdepth = 0.5 * (clip[..., 2] / w_safe) + 0.5
    on_screen = (px >= 0.0) & (px <= width) & (py >= 0.0) & (py <= height)
    valid = in_front & on_screen & jnp.isfinite(px) & jnp.isfinite(py)

    if prev_depth is not None:
        # Disocclusion: the previous frame's nearest pixel must hold this surface.
        ix = jnp.clip(jnp.floor(px), 0, width - 1).astype(jnp.int32)
        iy = jnp.clip(jnp.floor(py), 0, height - 1).astype(jnp.int32)
        seen = linear_depth(prev_depth[iy, ix], prev_cam)
        expected = w  # -z_view in frame t-1
        valid = valid & (jnp.abs(seen - expected) <= tol * jnp.abs(expected))

    return Reprojection(jnp.stack([px, py], axis=-1), valid, pdepth)


@partial(jax.jit, static_argnames=("width", "height"))
def reproject_pixels(depth, cam, prev_cam, prev_depth, width, height, tol):
    """``reproject`` without input checks or casts: arrays of one float dtype (tol a scalar)."""
    fn = jax.named_scope("reproject")(partial(_reproject_one, width=width, height=height,
                                              tol=tol))
    for _ in range(depth.ndim - 2):  # leading frame axes: cameras carry the same axes
        fn = jax.vmap(fn)
    return fn(depth, cam, prev_cam, prev_depth)


def check_depths(depth, prev_depth, width: int, height: int) -> None:
    shape = tuple(np.shape(depth))
    if len(shape) < 2 or shape[-2:] != (height, width):
        raise ValueError(f"reproject: depth must be (..., {height}, {width}), got {shape}")
    if prev_depth is not None and tuple(np.shape(prev_depth)) != shape:
        raise ValueError(f"reproject: prev_depth shape {np.shape(prev_depth)} != depth {shape}")


def _as(x, dtype):
    if isinstance(x, jax.Array):
        return x.astype(dtype)
    return jnp.asarray(np.asarray(x, dtype=dtype))


def reproject(depth, camera: Camera, prev_camera: Camera, width: int, height: int, *,
              prev_depth=None, depth_tolerance: float = DEFAULT_DEPTH_TOLERANCE,
              dtype=jnp.float32) -> Reprojection:
    """Positions in frame t-1 of the pixels of frame t, from exact camera motion.

    ``depth`` is frame t's window depth (H, W) in [0, 1] (VisBuffer.depth; empty pixels at 1.0
    are treated as points on the far plane). Pixels that land off screen in t-1, or behind its
    camera, are invalid; with ``prev_depth`` (frame t-1's depth) a pixel is also invalid where
    t-1 saw another surface there (nearest pixel, linear depths differing by more than
    ``depth_tolerance`` relative). Leading frame axes (T, H, W) are allowed when the cameras
    carry the same leading axes. ``dtype``: float32, or float64 (64-bit JAX enabled for the
    call only).
    """
    check_depths(depth, prev_depth, width, height)
    dt = np.dtype(dtype)
    if dt not in FLOAT_DTYPES:
        raise ValueError(f"dtype must be float32 or float64, got {dt}")
    wide = jax.enable_x64(True) if dt == np.float64 else contextlib.nullcontext()
    with wide:
        d = _as(depth, dt)
        pd = None if prev_depth is None else _as(prev_depth, dt)
        cam, prev = cast_camera(camera, dt), cast_camera(prev_camera, dt)
        return reproject_pixels(d, cam, prev, pd, int(width), int(height),
                                jnp.asarray(depth_tolerance, dt))
