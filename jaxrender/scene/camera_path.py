"""Camera paths for temporal studies: pan, orbit, dolly, sub-pixel jitter.

A path is a ``CameraPath``: ``cameras`` is one Camera whose arrays carry a leading frame axis T
(usable with ``jax.vmap`` or ``jax.lax.scan``), ``previous`` the camera of the frame before each
(frame 0's previous is itself), and ``jitter_px`` float32[T, 2] the sub-pixel offset each frame
was shifted by (0 unless made with ``jitter``). Iterating yields (camera, previous) per frame.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.scene.camera import Camera, look_at


class CameraPath(NamedTuple):
    cameras: Camera
    previous: Camera
    jitter_px: jax.Array

    def __len__(self) -> int:
        return int(self.cameras.eye.shape[0])

    def __iter__(self):
        for t in range(len(self)):
            yield frame(self.cameras, t), frame(self.previous, t)


def frame(batched: Camera, t: int) -> Camera:
    """Camera t of a batched camera."""
    return jax.tree_util.tree_map(lambda a: a[t], batched)


def stack(cameras: list[Camera]) -> Camera:
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *cameras)


def _path(cams: list[Camera], jitter=None) -> CameraPath:
    batched = stack(cams)
    prev = stack([cams[0]] + cams[:-1])
    j = jnp.zeros((len(cams), 2), jnp.float32) if jitter is None else jnp.asarray(jitter, jnp.float32)
    return CameraPath(batched, prev, j)


def _np(camera: Camera):
    return (np.asarray(camera.eye, np.float64), np.asarray(camera.rotation, np.float64),
            float(camera.fov_y), float(camera.near), float(camera.far))


def _make(eye, rotation, fov, near, far) -> Camera:
    return Camera(eye=jnp.asarray(eye, jnp.float32), rotation=jnp.asarray(rotation, jnp.float32),
                  fov_y=jnp.float32(fov), near=jnp.float32(near), far=jnp.float32(far))


def _yaw_pitch(rotation: np.ndarray, yaw: float, pitch: float) -> np.ndarray:
    """Rotate the camera about its own up axis by ``yaw`` then its right axis by ``pitch``
    (radians; positive yaw turns left, positive pitch turns up)."""
    def rot(axis, ang):
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        return np.eye(3) + np.sin(ang) * k + (1 - np.cos(ang)) * k @ k

    world = rot(rotation[1], yaw) @ rot(rotation[0], pitch)  # applied to world-space axes
    return (world @ rotation.T).T


def pixels_to_angle(pixels: float, camera: Camera, height: int) -> float:
    """The rotation that moves the image centre by ``pixels`` pixels."""
    f_px = height / (2.0 * np.tan(float(camera.fov_y) / 2.0))
    return float(np.arctan(pixels / f_px))


def pan(camera: Camera, n_frames: int, pixels_per_frame: float, height: int,
        direction: str = "horizontal") -> CameraPath:
    """Rotate in place so the image centre moves ``pixels_per_frame`` pixels per frame
    (horizontal: the scene moves left, the camera turns right; vertical: the camera tilts up)."""
    eye, rot, fov, near, far = _np(camera)
    step = pixels_to_angle(pixels_per_frame, camera, height)
    cams = []
    for t in range(n_frames):
        yaw, pitch = ((-step * t, 0.0) if direction == "horizontal" else (0.0, step * t))
        cams.append(_make(eye, _yaw_pitch(rot, yaw, pitch), fov, near, far))
    return _path(cams)


def orbit(center, radius: float, n_frames: int, degrees_per_frame: float, *, height: float = 1.0,
          start_deg: float = 0.0, fov_y_deg: float = 60.0, near: float = 0.1,
          far: float = 100.0) -> CameraPath:
    """Circle ``center`` at ``radius`` and ``height`` above it, always looking at it."""
    c = np.asarray(center, np.float64)
    cams = []
    for t in range(n_frames):
        a = np.deg2rad(start_deg + degrees_per_frame * t)
        eye = c + np.array([radius * np.sin(a), height, radius * np.cos(a)])
        cams.append(look_at(eye, c, fov_y_deg=fov_y_deg, near=near, far=far))
    return _path(cams)


def dolly(camera: Camera, n_frames: int, distance_per_frame: float) -> CameraPath:
    """Move along the view direction by ``distance_per_frame`` world units per frame."""
    eye, rot, fov, near, far = _np(camera)
    fwd = -rot[2]
    return _path([_make(eye + fwd * distance_per_frame * t, rot, fov, near, far)
                  for t in range(n_frames)])


def halton(n: int, base: int) -> np.ndarray:
    out = np.zeros(n)
    for i in range(n):
        f, r, k = 1.0, 0.0, i + 1
        while k > 0:
            f /= base
            r += f * (k % base)
            k //= base
        out[i] = r
    return out


def jitter(camera: Camera, n_frames: int, height: int, *, pattern: str = "halton") -> CameraPath:
    """Sub-pixel jitter (as TAA does): frame t is shifted by ``jitter_px[t]`` in [-0.5, 0.5)^2
    pixels (Halton 2, 3, or "none"). The Camera holds no projection offset, so the shift is
    made by rotating the camera: exact at the image centre, off by O(offset * x^2 / f^2) px at
    the edges (below 1e-2 px for fov <= 90 degrees). x right, y down, in pixels. Only the
    ``height`` sizes a pixel: the field of view is vertical and pixels are square."""
    eye, rot, fov, near, far = _np(camera)
    if pattern == "halton":
        offs = np.stack([halton(n_frames, 2), halton(n_frames, 3)], 1) - 0.5
    elif pattern == "none":
        offs = np.zeros((n_frames, 2))
    else:
        raise ValueError(f"jitter: unknown pattern {pattern!r} (halton, none)")
    cams = []
    for dx, dy in offs:
        # Image content moves by (dx, dy) when the camera turns the other way.
        yaw = pixels_to_angle(dx, camera, height)
        pitch = pixels_to_angle(dy, camera, height)
        cams.append(_make(eye, _yaw_pitch(rot, yaw, pitch), fov, near, far))
    return _path(cams, offs)


# ------------------------------------------------------------------ path types by name

REQUIRED = object()  # a parameter without a default


class PathParam(NamedTuple):
    kind: type  # float, str, or tuple (3 numbers)
    default: object = REQUIRED


class PathType(NamedTuple):
    """A camera path a study names by ``type``: ``build(camera, frames, width, height,
    **params)`` starts from the scene's default camera and returns a CameraPath or a list of
    cameras; ``params`` declares what a study may set. ``overridden``: (param, by) pairs where
    ``param`` has no effect once ``by`` is given, so a study may not set both."""

    build: Callable
    params: dict
    overridden: tuple[tuple[str, str], ...] = ()


def overridden_message(path_type: str, param: str, by: str) -> str:
    return (f"camera path {path_type!r}: {param!r} has no effect when {by!r} is given; set "
            f"one of them")


def _static(camera, frames, width, height):
    return [camera] * frames


def _pan(camera, frames, width, height, *, pixels_per_frame, direction="horizontal"):
    return pan(camera, frames, float(pixels_per_frame), height, direction=direction)


def _dolly(camera, frames, width, height, *, distance_per_frame):
    return dolly(camera, frames, float(distance_per_frame))


def _jitter(camera, frames, width, height, *, pattern="halton"):
    return jitter(camera, frames, height, pattern=pattern)


ORBIT_OVERRIDDEN = (("distance", "center"),)  # distance places the centre that is not given


def _orbit(camera, frames, width, height, *, degrees_per_frame, distance=None, center=(),
           radius=0.0):
    """Around ``center`` (default: the point ``distance``, 4 units, ahead of the camera),
    starting where the camera stands, at ``radius`` (0: the camera's distance from the centre
    in the ground plane)."""
    if distance is not None and len(center):
        raise ValueError(overridden_message("orbit", "distance", "center"))
    eye = np.asarray(camera.eye, np.float64)
    fwd = -np.asarray(camera.rotation, np.float64)[2]
    c = np.asarray(center if len(center) else eye + fwd * (4.0 if distance is None else distance))
    rel = eye - c
    radius = float(radius or np.hypot(rel[0], rel[2]) or 1.0)
    return orbit(c, radius, frames, float(degrees_per_frame), height=rel[1],
                 start_deg=float(np.rad2deg(np.arctan2(rel[0], rel[2]))),
                 fov_y_deg=float(np.rad2deg(float(camera.fov_y))),
                 near=float(camera.near), far=float(camera.far))


PATH_TYPES: dict[str, PathType] = {
    "static": PathType(_static, {}),
    "pan": PathType(_pan, {"pixels_per_frame": PathParam(float),
                           "direction": PathParam(str, "horizontal")}),
    "orbit": PathType(_orbit, {"degrees_per_frame": PathParam(float),
                               "distance": PathParam(float, 4.0),
                               "center": PathParam(tuple, ()),
                               "radius": PathParam(float, 0.0)}, ORBIT_OVERRIDDEN),
    "dolly": PathType(_dolly, {"distance_per_frame": PathParam(float)}),
    "jitter": PathType(_jitter, {"pattern": PathParam(str, "halton")}),
}
