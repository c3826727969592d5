"""The motion field of a camera path over a (possibly moving) scene: for every frame t >= 1, where
each pixel of frame t was in frame t-1 and whether that point was visible there. The temporal
metrics warp frame t-1 with it (``metrics.warp_error``), so moving objects are warped where
camera-only reprojection would tear them.

Covered pixels move with their motion vectors (``raster.motion``), validated against the previous
frame's depth; empty pixels move as the far plane under the camera. It runs as a sequence of
the one program (``program.render_sequence``) like a pipeline, with the previous depth and
camera as its state; it is not registered, since it renders no image.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp

from jaxrender.pipelines import program
from jaxrender.pipelines.registry import Pipeline, RenderConfig
from jaxrender.pipelines.visibility import Previous, visibility
from jaxrender.raster.motion import reproject_with_motion
from jaxrender.scene.animation import positions_at
from jaxrender.scene.camera_path import stack
from jaxrender.scene.reprojection import DEFAULT_DEPTH_TOLERANCE, Reprojection, reproject_pixels
from jaxrender.types import Frame


@dataclass(frozen=True)
class _Settings(RenderConfig):
    """A visibility pass's settings: the default fragment capacity and dispatch chunk."""

    chunk: int = 0

    @property
    def capacity(self) -> int:
        return 4 * self.width * self.height


def _init(scene, static, camera, cfg):
    return jnp.ones((cfg.height, cfg.width), jnp.float32), camera, jnp.asarray(False)


def _step(scene, static, state, camera, t, cfg):
    prev_depth, prev_camera, has_prev = state
    w, h = cfg.width, cfg.height
    vis = visibility(scene, camera, cfg, previous=Previous(positions_at(scene, t - 1),
                                                           prev_camera))
    covered = vis.tri_id >= 0
    moved = reproject_with_motion(vis.motion, vis.prev_depth, covered, camera, prev_camera,
                                  prev_depth, DEFAULT_DEPTH_TOLERANCE)
    far = reproject_pixels(jnp.ones((h, w), jnp.float32), camera, prev_camera, None, w, h,
                           jnp.float32(0.0))
    position = jnp.where(covered[..., None], moved.position, far.position)
    valid = jnp.where(covered, moved.valid, far.valid) & has_prev
    frame = Frame(jnp.zeros((h, w, 3), jnp.float32), {"overflow": vis.counts["overflow"]},
                  {"position": position, "valid": valid})
    return frame, (vis.depth, camera, jnp.asarray(True))


MOTION_FIELD = Pipeline("motion_field", _Settings, _step, _init,
                        description="the motion field of a camera path")


def motion_field(scene, cameras, width: int, height: int, *, start: int = 0) -> Reprojection:
    """Reprojection (T-1, H, W) of frames 1..T-1 of ``cameras`` (a list, a CameraPath or a
    batched Camera; frame i is frame ``start + i`` of the scene's clock) into their previous
    frames: positions, validity and (unused here) depths."""
    if isinstance(cameras, list):
        cameras = stack(cameras)
    frames = program.render_sequence(MOTION_FIELD, scene, cameras,
                                     _Settings(width=width, height=height), start=start)
    pos, valid = frames.aux["position"][1:], frames.aux["valid"][1:]
    return Reprojection(pos, valid, jnp.zeros(valid.shape, jnp.float32))


__all__ = ["MOTION_FIELD", "motion_field"]
