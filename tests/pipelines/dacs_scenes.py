"""Tiny Lambert scenes for the checkerboard and DACS tests, all of one shape (same vertex and
triangle counts, padded with degenerate triangles, same effects) so each pipeline compiles once
for all of them. Camera at the origin looking down -Z, 90 degree vertical field of view."""

from __future__ import annotations

import functools

import numpy as np

from jaxrender.scene import Material, MeshPart, build_scene, look_at, make_lights

W, H = 32, 24  # multiples of 4: level 0 is exactly 1/16 of the pixels
N_RECTS = 4  # every scene: 4 rectangles (8 triangles), unused ones degenerate


def _rect(x0, y0, x1, y1, d, tilt, material, width=W, height=H) -> MeshPart:
    """Window-space rectangle [x0, x1) x [y0, y1) at view distance d."""
    aspect = width / height
    xy = np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], np.float64)
    pos = np.stack([(2 * xy[:, 0] / width - 1) * aspect * d, (1 - 2 * xy[:, 1] / height) * d,
                    np.full(4, -d)], 1)
    nrm = np.array([[-tilt, tilt, 1.0], [tilt, tilt, 1.0], [tilt, -tilt, 1.0], [-tilt, -tilt, 1.0]])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return MeshPart(pos, np.array([[0, 2, 1], [0, 3, 2]]), normals=nrm, material=material)


def _degenerate() -> MeshPart:
    return MeshPart(np.zeros((4, 3)) + [0.0, 0.0, -50.0], np.array([[0, 1, 2], [0, 2, 3]]),
                    normals=np.tile([0.0, 0.0, 1.0], (4, 1)), material=0)


def _scene(parts, name):
    parts = list(parts) + [_degenerate() for _ in range(N_RECTS - len(parts))]
    mats = [Material("grey", albedo=(0.7, 0.7, 0.7)), Material("red", albedo=(0.9, 0.2, 0.1))]
    lights = make_lights([((0.3, 0.5, 1.0), 1.5)], ambient=0.05)
    cam = look_at((0, 0, 0), (0, 0, -1), fov_y_deg=90.0, near=0.1, far=100.0)
    return build_scene(parts, mats, [], lights, cam, name="dacs_test")  # one static name


@functools.cache
def flat_scene():
    """One object, one material, constant normal: a single id and a constant colour."""
    return _scene([_rect(-4, -4, W + 4, H + 4, 10.0, 0.0, 0)], "flat")


@functools.cache
def shapes_scene():
    """A covering, shaded background and two nearer rectangles of other objects and materials
    (depth and id edges inside the image)."""
    return _scene([_rect(-4, -4, W + 4, H + 4, 10.0, 0.6, 0),
                   _rect(5, 3, 17, 15, 4.0, 0.3, 1),
                   _rect(20, 9, 29, 21, 6.0, -0.4, 0)], "shapes")
