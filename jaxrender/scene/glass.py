"""The built-in scene ``glass``: tinted glass panes and additive particle quads over a textured,
lit background, so that every pipeline's transparent pass has work: several overlapping layers
per pixel (the panes cross, the particles cluster in front of them), layers over the opaque
objects and over the empty sky, some panes and particles partly off screen."""

from __future__ import annotations

import numpy as np

from jaxrender.scene.camera import look_at
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import box, grid_plane, trs_matrix, uv_sphere
from jaxrender.scene.scene import Scene, build_scene

PANE_TINTS = ((0.55, 0.8, 1.0), (1.0, 0.55, 0.45), (0.6, 1.0, 0.55), (1.0, 0.9, 0.4))


def tile_image(n: int = 128, tiles: int = 8) -> np.ndarray:
    """Stone tiles with grout lines (RGBA, opaque)."""
    t = (np.arange(n) + 0.5) / n * tiles
    grout = (np.minimum(t % 1, 1 - t % 1) < 0.06)
    line = grout[:, None] | grout[None, :]
    shade = 0.6 + 0.3 * ((np.floor(t)[:, None] + np.floor(t)[None, :]) % 2)
    rgb = np.where(line[..., None], [0.25, 0.25, 0.28], shade[..., None] * [0.9, 0.85, 0.75])
    return np.concatenate([rgb, np.ones((n, n, 1))], -1)


def spark_image(n: int = 32) -> np.ndarray:
    """A soft round particle: warm colour, alpha falling from 1 at the centre to 0 at the rim."""
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n * 2 - 1
    alpha = np.clip(1.0 - (x * x + y * y), 0.0, 1.0) ** 2
    rgb = np.broadcast_to([1.0, 0.75, 0.35], (n, n, 3))
    return np.concatenate([rgb, alpha[..., None]], -1)


def _panes(n_panes: int, first_material: int) -> list:
    """Panes crossing each other at staggered depths; the first reaches past the left edge."""
    parts = []
    for i in range(n_panes):
        x = -1.9 + 3.4 * i / max(n_panes - 1, 1)
        z = 0.6 - 0.7 * (i % 3)
        yaw = (-25.0, 20.0, -10.0, 30.0)[i % 4]
        size = (2.6 if i == 0 else 1.5, 1.8)
        pane = grid_plane(size, material=first_material + i % len(PANE_TINTS))
        parts.append(pane.transformed(trs_matrix((x, 1.1, z), (90, yaw, 0))))
    return parts


def _particles(n_particles: int, material: int, seed: int) -> list:
    """Camera-facing quads in a cloud in front of the panes, some leaving the screen."""
    rng = np.random.default_rng(seed)
    parts = []
    for _ in range(n_particles):
        pos = (rng.uniform(-2.8, 2.8), rng.uniform(0.5, 2.1), rng.uniform(0.4, 1.8))
        size = rng.uniform(0.25, 0.6)
        quad = grid_plane((size, size), material=material)
        parts.append(quad.transformed(trs_matrix(pos, (90, 0, 0))))
    return parts


def glass(*, n_panes: int = 4, n_particles: int = 24, seed: int = 0,
          texture_size: int = 128) -> Scene:
    """Glass panes and additive particles over a textured, lit room (transparency)."""
    mats = [
        Material("floor", albedo=(1, 1, 1), texture=0),
        Material("wall", albedo=(0.8, 0.8, 0.85), texture=0),
        Material("statue", albedo=(0.7, 0.3, 0.2), specular=(0.3,) * 3, shininess=60,
                 brdf="blinn_phong"),
        Material("crate", albedo=(0.35, 0.5, 0.3)),
    ]
    first_pane = len(mats)
    mats += [Material(f"pane{i}", albedo=tint, blend="over", opacity=0.35 + 0.1 * (i % 3))
             for i, tint in enumerate(PANE_TINTS)]
    spark = len(mats)
    mats.append(Material("spark", albedo=(1, 1, 1), texture=1, blend="additive", opacity=0.8,
                         opacity_source="texture_alpha", emissive=(0.6, 0.4, 0.15)))
    parts = [
        grid_plane((12.0, 12.0), uv_scale=(6, 6), material=0),
        grid_plane((12.0, 4.0), uv_scale=(6, 2), material=1).transformed(
            trs_matrix((0, 2.0, -3.0), (90, 0, 0))),
        uv_sphere(0.55, 12, 24, material=2).transformed(trs_matrix((0.4, 0.55, -1.2))),
        box((0.8, 0.8, 0.8), material=3).transformed(trs_matrix((-1.3, 0.4, -1.8), (0, 25, 0))),
    ]
    parts += _panes(int(n_panes), first_pane) + _particles(int(n_particles), spark, seed)
    lights = make_lights([((0.4, 0.8, 0.5), 2.2)], [((1.5, 2.5, 1.0), (1.5, 1.4, 1.2))],
                         ambient=0.12)
    cam = look_at((0.0, 1.3, 4.2), (0.0, 1.0, 0.0), fov_y_deg=55)
    return build_scene(parts, mats, [tile_image(texture_size), spark_image()], lights, cam,
                       name="glass", description=glass.__doc__.splitlines()[0])
