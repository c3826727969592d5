"""Hard cases of shading and sampling: extreme specular exponents, bad normals, degenerate uvs,
texture minification and magnification, flat, noisy, empty and tiny images."""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrender.scene.hard_layout import (BACKDROP, NOISE, OBJECT, SECOND, backdrop, case_camera,
                                         case_lights, case_scene, sphere)
from jaxrender.scene.mesh import grid_plane
from jaxrender.scene.scene import Scene


def _phong(exponent: float, name: str, doc: str) -> Scene:
    mat = dataclasses.replace(OBJECT, shininess=float(exponent))
    return case_scene(name, [backdrop(), sphere(0.9, lat=16, lon=24)], case_camera(),
                      lights=case_lights(point=((0.0, 0.0, 2.5), 8.0)), doc=doc,
                      materials=(BACKDROP, mat, SECOND, NOISE))


def phong_1e4() -> Scene:
    """A Blinn-Phong sphere of exponent 1e4 lit from the eye.

    Stresses: cos^n for large n (underflow, 0 * inf), the energy normalisation (n + 8)/(8 pi)
    = 400. Must hold: finite, the highlight bounded, error in bound."""
    return _phong(1e4, "hard_phong_1e4", phong_1e4.__doc__)


def phong_1e6() -> Scene:
    """The same sphere at exponent 1e6 (normalisation 4e4, lobe narrower than float32 can
    resolve away from the peak). Must hold: finite, error in bound."""
    return _phong(1e6, "hard_phong_1e6", phong_1e6.__doc__)


def bad_normals() -> Scene:
    """A sphere whose vertex normals are zero, 1e-30 long (their square underflows), 1e15 long
    and randomly scaled, beside an unnormalised wall.

    Stresses: normalisation of zero and near-zero vectors, interpolation of normals of wildly
    different lengths. Must hold: finite; zero normals fall back to the geometric normal."""
    s = sphere(0.8, (0.3, 0.0, 0.0))
    k = np.arange(len(s.normals)) % 4
    scale = np.select([k == 0, k == 1, k == 2], [0.0, 1e-30, 1e15],
                      np.random.default_rng(4).uniform(0.1, 10.0, len(k)))
    s.normals = s.normals * scale[:, None]
    wall = backdrop()
    wall.normals = wall.normals * 7.5
    return case_scene("hard_bad_normals", [wall, s], case_camera(), doc=bad_normals.__doc__)


def zero_area_uv() -> Scene:
    """Textured surfaces whose UV charts have zero area: a wall with every uv equal, a sphere
    whose uvs are collinear.

    Stresses: texture derivatives of 0 (LOD = log2(0)), tangent frames from a singular uv
    Jacobian, object-space charts of zero area. Must hold: finite, error in bound."""
    wall = backdrop()
    wall.uvs = np.full_like(wall.uvs, 0.3)
    s = sphere(0.8, material=3)
    s.uvs = np.stack([s.uvs[:, 0], s.uvs[:, 0]], 1)  # on the line u = v
    return case_scene("hard_zero_area_uv", [wall, s], case_camera(), doc=zero_area_uv.__doc__)


def minify() -> Scene:
    """A noise-textured floor to the horizon with 1e4 texture repeats (extreme minification:
    thousands of texels per pixel, the coarsest MIP levels and beyond).

    Must hold: finite, colours tend to the texture mean, error in bound."""
    floor = grid_plane((1000, 1000), (4, 4), uv_scale=(1e4, 1e4), material=3)
    return case_scene("hard_minify", [floor],
                      case_camera((0, 1.0, 0), (0, 0.0, -8), near=0.05, far=2000.0),
                      doc=minify.__doc__)


def magnify() -> Scene:
    """A checker wall seen from 1e-3 away with uvs spanning 1e-4 (one texel fills the screen
    thousands of times over: LOD far below 0).

    Must hold: finite, the magnification filter clamps at level 0, error in bound."""
    wall = backdrop(z=-1e-3, size=0.1, uv_scale=(1e-4, 1e-4))
    return case_scene("hard_magnify", [wall],
                      case_camera((0, 0, 0), (0, 0, -1), near=1e-4, far=1.0),
                      doc=magnify.__doc__)


def flat() -> Scene:
    """One untextured Lambert wall filling the view, lit by a directional light only: every
    pixel has the same colour (DACS: all neighbours equal, variance exactly 0).

    Must hold: every pipeline's image is that constant (within float rounding), so error 0."""
    wall = backdrop(material=2)
    return case_scene("hard_flat", [wall], case_camera(),
                      lights=case_lights(point=((0, 0, 2.5), 0.0), sun=((0.0, 0.0, 1.0), 1.5),
                                     ambient=0.0),
                      doc=flat.__doc__)


def noise() -> Scene:
    """A wall with a binary white-noise texture magnified to about 2 pixels per texel, so the
    MIP filter cannot average it away (DACS: neighbours dissimilar nearly everywhere, so it must
    fall back to shading nearly every pixel rather than interpolate noise).

    Must hold: finite, error in bound."""
    wall = backdrop(material=3, uv_scale=(0.5, 0.5))
    return case_scene("hard_noise", [wall], case_camera(), doc=noise.__doc__)


def empty() -> Scene:
    """Geometry only behind the camera: nothing is visible.

    Stresses: empty work lists (zero chunks), empty coverage, metrics of an all-background
    image. Must hold: the image is background (0) and shading counts are 0."""
    return case_scene("hard_empty", [backdrop(z=5.0), sphere(centre=(0, 0, 4.0))], case_camera(),
                      doc=empty.__doc__)


def tiny_image() -> Scene:
    """The reference sphere-and-wall scene for degenerate image sizes: 1 pixel wide (1x16) and
    4096 x 1 (``HardCase.resolutions``).

    Stresses: pixel blocks (quads, 4x4 DACS blocks, 8x8 chunks) cut by the image border, an
    aspect of 1/16 and of 4096. Must hold: finite, error in bound."""
    return case_scene("hard_tiny_image", [backdrop(), sphere()], case_camera(),
                      doc=tiny_image.__doc__)
