"""A striped quad sliding whole pixels per frame in front of a wall, under a still camera: what
motion vectors are for (camera-only reprojection fetches each pixel's own previous colour,
a stripe off)."""

import functools

import numpy as np

from jaxrender.scene import build_scene
from jaxrender.scene.animation import ObjectMotion
from jaxrender.scene.camera import look_at
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import grid_plane, trs_matrix

W, H, FPS = 32, 24, 60.0
PX_PER_FRAME = 2.0  # whole pixels: the nearest previous sample is the surface point itself
CAMERA = look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_y_deg=50.0)


@functools.lru_cache(maxsize=None)
def sliding_scene():
    world_per_px = 2 * 4.0 * np.tan(np.deg2rad(25.0)) / H
    quad = grid_plane((2.0, 2.0), (2, 2)).transformed(trs_matrix((-0.4, 0, 0), (90, 0, 0)))
    quad.motion = ObjectMotion(velocity=(PX_PER_FRAME * world_per_px * FPS, 0.0, 0.0))
    back = grid_plane((8.0, 8.0), material=1).transformed(trs_matrix((0, 0, -1.0), (90, 0, 0)))
    mats = [Material("stripes", albedo=(0.9, 0.9, 0.9), procedural="stripes",
                     stripe_resolution=4.0), Material("wall", albedo=(0.3, 0.3, 0.3))]
    return build_scene([quad, back], mats, [], make_lights([((0, 0, 1), 1.0)]), CAMERA,
                       name="slide", fps=FPS)
