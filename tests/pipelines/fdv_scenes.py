"""Scenes for the forward / deferred / visbuffer tests: axis-aligned rectangles and triangles
given in window (pixel) coordinates, so that coverage can be worked out by hand.

The camera sits at the origin looking down -Z with a 90 degree vertical field of view; a
window point (x, y) at view distance d maps to world (( 2x/W - 1) * aspect * d, (1 - 2y/H) d, -d).
Every scene is padded to the same shape (PAD_T triangles, two materials) so that each pipeline
compiles once per configuration for all of them.
"""

from __future__ import annotations

import numpy as np

from jaxrender.scene import Material, MeshPart, build_scene, look_at, make_lights

W, H = 16, 16
PAD_T = 8


def window_to_world(xy, d, width=W, height=H):
    xy = np.asarray(xy, np.float64)
    aspect = width / height
    x = (2.0 * xy[:, 0] / width - 1.0) * aspect * d
    y = (1.0 - 2.0 * xy[:, 1] / height) * d
    return np.stack([x, y, np.full_like(x, -d)], 1)


def tri_part(corners, d, material=0, width=W, height=H) -> MeshPart:
    pos = window_to_world(corners, d, width, height)
    return MeshPart(pos, np.array([[0, 1, 2]]), normals=np.tile([0.0, 0.0, 1.0], (3, 1)),
                    material=material)


def rect_part(x0, y0, x1, y1, d, material=0, width=W, height=H) -> MeshPart:
    pos = window_to_world([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], d, width, height)
    return MeshPart(pos, np.array([[0, 2, 1], [0, 3, 2]]),
                    normals=np.tile([0.0, 0.0, 1.0], (4, 1)), material=material)


def make_scene(parts, *, width=W, height=H, pad_to=PAD_T, materials=None, name="fdv"):
    n = sum(len(p.faces) for p in parts)
    if n < pad_to:  # degenerate triangles: never covered
        parts = list(parts) + [MeshPart(np.zeros((3, 3)), np.zeros((pad_to - n, 3), np.int64),
                                        normals=np.tile([0.0, 0.0, 1.0], (3, 1)))]
    mats = materials or [Material("red", albedo=(0.8, 0.2, 0.2)),
                         Material("blue", albedo=(0.2, 0.3, 0.8), specular=(0.3,) * 3,
                                  shininess=20.0, brdf="blinn_phong")]
    cam = look_at((0, 0, 0), (0, 0, -1), fov_y_deg=90.0, near=0.5, far=50.0)
    lights = make_lights([((0.3, 0.5, 1.0), 2.0)], [((1.0, 1.0, 1.0), 3.0)], ambient=0.1)
    return build_scene(parts, mats, [], lights, cam, name=name)
