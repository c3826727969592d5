"""Analytic transparent scenes: flat quads facing the camera, lit by ambient light alone, so a
surface's radiance is its albedo and a composite can be computed by hand."""

from __future__ import annotations

import numpy as np

from jaxrender.scene.camera import look_at
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import grid_plane, trs_matrix
from jaxrender.scene.scene import build_scene

BACKGROUND = (0.2, 0.3, 0.4)


def quad(z: float, material: int, size=(1.6, 1.6), x=0.0):
    """A quad at depth z facing +Z (the camera), covering the middle of the screen."""
    return grid_plane(size, material=material).transformed(trs_matrix((x, 0.0, z), (90, 0, 0)))


RED, GREEN, BLUE = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.1, 0.2, 1.0)
# (albedo, opacity, blend, z) front to back
TWO = [(RED, 0.5, "over", 0.5), (GREEN, 0.5, "over", 0.0)]
THREE = [(RED, 0.4, "over", 0.6), (BLUE, 0.7, "additive", 0.2), (GREEN, 0.6, "over", -0.4)]


def layered_quads(layers, order=None, *, background=True, name="quads"):
    """layers: (albedo rgb, opacity, blend, z) front to back or in any order; ``order`` the
    submission order (indices into layers; default as given). Returns the scene."""
    order = list(range(len(layers))) if order is None else list(order)
    mats = [Material("bg", albedo=BACKGROUND)]
    parts = [quad(-2.0, 0, size=(8.0, 8.0))] if background else []
    for i in order:
        albedo, a, blend, z = layers[i]
        mats.append(Material(f"layer{i}", albedo=albedo, blend=blend, opacity=a))
        parts.append(quad(z, len(mats) - 1))
    cam = look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0), fov_y_deg=40)
    return build_scene(parts, mats, [], make_lights([], ambient=1.0), cam, name=name)


def over(layers_back_to_front, background):
    """The hand-computed blend of (rgb, a, blend) layers, the first drawn first."""
    c = np.asarray(background, np.float64)
    for rgb, a, blend in layers_back_to_front:
        rgb = np.asarray(rgb, np.float64)
        c = c + a * rgb if blend == "additive" else a * rgb + (1 - a) * c
    return c
