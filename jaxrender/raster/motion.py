"""Motion vectors as Decima writes them for its visibility buffer: the barycentrics of the
triangle a pixel sees, applied to the same triangle's vertices projected by the previous frame
("previous HPOS"), give where that surface point was; the vector is that position minus where
the same barycentrics put it now. Clip coordinates are affine in the vertex positions, so
perspective-correct barycentrics interpolate them exactly: the vector is exact for any motion
that is affine per triangle (rigid motion, camera motion), and the vertex motion interpolated
linearly otherwise (vertex animation).

Both projections are unjittered (``camera.without_jitter``), so a jittered frame's vectors are
the surface's own motion, which is what a temporal resolve needs.

``disoccluded`` flags the pixels whose surface the previous frame did not show: off screen
there, or the previous pixels around the reprojected point do not hold the same object at the
depth the point had.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.scene.camera import Camera, without_jitter, world_to_clip
from jaxrender.scene.reprojection import Reprojection, linear_depth
from jaxrender.types import Array


def _window(clip: Array, faces_of_pixel: Array, bary: Array, width: int, height: int):
    """Window (x, y, depth) of the barycentric combination of each pixel's triangle."""
    c = jnp.sum(clip[faces_of_pixel] * bary[..., None], axis=-2)  # [..., 4]
    w = c[..., 3]
    ws = jnp.where(w > 0.0, w, 1.0)
    x = (c[..., 0] / ws + 1.0) * (0.5 * width)
    y = (1.0 - c[..., 1] / ws) * (0.5 * height)
    return x, y, 0.5 * (c[..., 2] / ws) + 0.5, w > 0.0


def motion_vectors(tri_id: Array, bary: Array, faces: Array, positions: Array,
                   camera: Camera, prev_positions: Array, prev_camera: Camera, width: int,
                   height: int) -> tuple[Array, Array]:
    """(motion float32[..., H, W, 2], prev_depth float32[..., H, W]) of a visibility buffer's
    ``tri_id`` and ``bary``: the window offset from this frame to the previous one of each
    covered pixel's surface point (x right, y down, pixels; 0 where empty), and that point's
    window depth in the previous frame (1.0 where empty or behind the previous camera)."""
    aspect = width / height
    now = world_to_clip(positions, without_jitter(camera), aspect)
    before = world_to_clip(prev_positions, without_jitter(prev_camera), aspect)
    covered = tri_id >= 0
    f = faces[jnp.maximum(tri_id, 0)]
    x0, y0, _, _ = _window(now, f, bary, width, height)
    x1, y1, z1, in_front = _window(before, f, bary, width, height)
    ok = covered & in_front
    motion = jnp.where(ok[..., None], jnp.stack([x1 - x0, y1 - y0], axis=-1), 0.0)
    return motion, jnp.where(ok, z1, 1.0)


def previous_position(motion: Array) -> Array:
    """float32[H, W, 2] window position in the previous frame of each pixel centre."""
    h, w = motion.shape[-3], motion.shape[-2]
    x = jnp.arange(w, dtype=jnp.float32)[None, :] + 0.5
    y = jnp.arange(h, dtype=jnp.float32)[:, None] + 0.5
    centre = jnp.stack(jnp.broadcast_arrays(x, y), axis=-1)
    return centre + motion


def _jitter_px(camera: Camera, width: int, height: int) -> Array:
    if camera.jitter is None:
        return jnp.zeros((2,), jnp.float32)
    return jnp.stack([camera.jitter[0] * (0.5 * width), -camera.jitter[1] * (0.5 * height)])


def reproject_with_motion(motion: Array, prev_depth: Array, covered: Array, camera: Camera,
                          prev_camera: Camera, prev_depth_buffer: Array | None,
                          tolerance) -> Reprojection:
    """``scene.reprojection.reproject`` from motion vectors: where each covered pixel's surface
    point was in the previous frame as it was rendered (its projection jitter included), valid
    where on screen, in front of that camera and, with ``prev_depth_buffer``, not hidden there
    (the nearest pixel's linear depth within ``tolerance`` relative). Moving objects reproject
    where camera-only reprojection cannot."""
    h, w = covered.shape
    shift = _jitter_px(prev_camera, w, h) - _jitter_px(camera, w, h)
    position = previous_position(motion) + shift[None, None, :]
    px, py = position[..., 0], position[..., 1]
    valid = covered & (prev_depth < 1.0) & (px >= 0.0) & (px <= w) & (py >= 0.0) & (py <= h)
    if prev_depth_buffer is not None:
        ix = jnp.clip(jnp.floor(px), 0, w - 1).astype(jnp.int32)
        iy = jnp.clip(jnp.floor(py), 0, h - 1).astype(jnp.int32)
        seen = linear_depth(prev_depth_buffer[iy, ix], prev_camera)
        expected = linear_depth(prev_depth, prev_camera)
        valid = valid & (jnp.abs(seen - expected) <= tolerance * jnp.abs(expected))
    return Reprojection(position, valid, prev_depth)


def disoccluded(position: Array, prev_depth: Array, objects: Array, prev_depth_buffer: Array,
                prev_objects: Array, prev_camera: Camera, tolerance: float) -> Array:
    """bool[H, W]: the previous frame did not show this pixel's surface. ``position``: its
    window position there; ``prev_depth``: its window depth there; ``objects``: its object id
    (-1 for empty pixels, whose surface is the far plane); ``prev_depth_buffer`` and
    ``prev_objects``: what the previous frame saw.

    The surface was seen when, among the 3x3 previous pixels around the nearest one, some show
    the same object and the point's linear depth lies within their range, widened by its own
    span (one pixel's extrapolation) and by ``tolerance`` relative: a jittered frame samples
    each pixel up to a pixel away from the last one, so on a sloped surface no single previous
    pixel need hold the point's depth, and at a silhouette or the image border the point can lie
    beyond the neighbours' depths."""
    h, w = objects.shape
    xn = jnp.floor(position[..., 0]).astype(jnp.int32)
    yn = jnp.floor(position[..., 1]).astype(jnp.int32)
    expected = linear_depth(prev_depth, prev_camera)
    lo = jnp.full((h, w), jnp.inf, jnp.float32)
    hi = jnp.full((h, w), -jnp.inf, jnp.float32)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            x, y = jnp.clip(xn + dx, 0, w - 1), jnp.clip(yn + dy, 0, h - 1)
            got = linear_depth(prev_depth_buffer[y, x], prev_camera)
            same = prev_objects[y, x] == objects
            lo = jnp.where(same, jnp.minimum(lo, got), lo)
            hi = jnp.where(same, jnp.maximum(hi, got), hi)
    span = jnp.where(hi >= lo, hi - lo, 0.0)  # a pixel's sampling offset can leave the range
    seen = ((expected >= (lo - span) * (1.0 - tolerance))
            & (expected <= (hi + span) * (1.0 + tolerance)))
    on_screen = ((position[..., 0] >= 0.0) & (position[..., 0] <= w)
                 & (position[..., 1] >= 0.0) & (position[..., 1] <= h))
    return ~(seen & on_screen)


__all__ = ["disoccluded", "motion_vectors", "previous_position", "reproject_with_motion"]
