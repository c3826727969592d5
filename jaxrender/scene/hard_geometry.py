"""Hard cases of geometry: degenerate and sliver triangles, sub-pixel and near-plane geometry,
far coordinates, coplanar surfaces, extreme fields of view, grazing angles."""

from __future__ import annotations

import numpy as np

from jaxrender.scene.camera import look_at
from jaxrender.scene.hard_layout import (backdrop, case_camera, case_lights, case_scene,
                                         sphere, triangle_soup)
from jaxrender.scene.mesh import MeshPart, grid_plane, trs_matrix, uv_sphere
from jaxrender.scene.scene import Scene

def degenerate() -> Scene:
    """Degenerate and collinear triangles in front of a textured wall.

    Stresses: zero-area set-up (edge functions all 0, 1/area), repeated vertices, exactly
    collinear and nearly collinear (1e-7 off the line) triangles, and one of them lying on pixel
    centres. Must hold: none of them covers a sample (the image is the wall alone) and nothing
    divides by their zero area."""
    rng = np.random.default_rng(1)
    tris = []
    for _ in range(48):
        a, b = rng.uniform(-1.5, 1.5, 3), rng.uniform(-1.5, 1.5, 3)
        a[2] = b[2] = 0.0
        kind = len(tris) % 4
        if kind == 0:
            tris.append([a, a, a])  # a point
        elif kind == 1:
            tris.append([a, b, a])  # repeated vertex
        elif kind == 2:
            tris.append([a, (a + b) / 2, b])  # exactly collinear
        else:
            tris.append([a, b, 0.3 * a + 0.7 * b + [0, 1e-7, 0]])  # 1e-7 off the line
    return case_scene("hard_degenerate", [backdrop(), triangle_soup(tris)], case_camera(),
                      doc=degenerate.__doc__)


def sliver() -> Scene:
    """A closed fan of 200 slivers around a centre, angles from 1e-6 rad (aspect >= 1e6) to
    large, plus 40 free slivers of aspect 1e6 across the screen.

    Stresses: edge functions of nearly parallel edges, snapping of needle vertices, 1/area for
    areas of 1e-6 px. Must hold: the fan covers its disc watertight (no wall shows through, no
    sample twice: the fan is one surface) and barycentrics stay finite."""
    n = 200
    tiny = np.full(n - 8, 1e-6)
    big = np.full(8, (2 * np.pi - tiny.sum()) / 8)
    ang = np.concatenate([[0.0], np.cumsum(np.concatenate([big[:4], tiny, big[4:]]))])
    ang[-1] = 0.0  # close the fan exactly on its first rim vertex
    rim = np.stack([1.2 * np.cos(ang), 1.2 * np.sin(ang), np.zeros_like(ang)], 1)
    pos = np.concatenate([[[0.0, 0.0, 0.0]], rim[:-1]])
    k = np.arange(n)
    faces = np.stack([np.zeros(n, int), 1 + k, 1 + (k + 1) % n], 1)
    fan = MeshPart(pos, faces, np.tile([0.0, 0.0, 1.0], (len(pos), 1)), pos[:, :2] * 0.25,
                   material=1)
    rng = np.random.default_rng(2)
    free = []
    for _ in range(40):
        c = rng.uniform(-1.5, 1.5, 2)
        t = rng.uniform(0, np.pi)
        d = np.array([np.cos(t), np.sin(t)])
        nrm = np.array([-d[1], d[0]])
        p0, p1 = c - 1.5 * d, c + 1.5 * d
        p2 = c + 3e-6 * nrm  # height 3e-6 over a base of 3: aspect 1e6
        free.append([[*p0, 0.5], [*p1, 0.5], [*p2, 0.5]])
    return case_scene("hard_sliver", [backdrop(), fan, triangle_soup(free, material=2)],
                      case_camera(),
                      doc=sliver.__doc__)


def subpixel(*, n_triangles: int = 400) -> Scene:
    """n_triangles triangles of 1e-4 px^2 each scattered over a wall (at 24x16).

    Stresses: fixed-point snapping of triangles far below the sub-pixel grid, derivatives of
    barycentrics of a tiny triangle (huge), quad helper lanes. Must hold: finite, and coverage
    agrees with the exact reference rule (nearly none is covered)."""
    rng = np.random.default_rng(3)
    # 24 px span about 2.89 world units at z = 0 from the default camera: 1 px ~ 0.12 units.
    px = 2 * 2.5 * np.tan(np.deg2rad(30)) / 16
    side = np.sqrt(2e-4) * px  # a right triangle of legs s has area s^2 / 2 = 1e-4 px^2
    c = np.concatenate([rng.uniform(-1.6, 1.6, (n_triangles, 2)), np.zeros((n_triangles, 1))], 1)
    tris = np.stack([c, c + [side, 0, 0], c + [0, side, 0]], 1)
    return case_scene("hard_subpixel", [backdrop(), triangle_soup(tris)], case_camera(),
                      doc=subpixel.__doc__)


def near_plane() -> Scene:
    """A floor from behind the eye to far away, a wall that passes through the eye, and large
    triangles with vertices behind the eye.

    Stresses: homogeneous clipping against the near plane, vertices with w < 0 (behind the
    eye), perspective-correct attributes of clipped polygons. Must hold: nothing behind the eye
    is drawn, the visible parts are clipped not dropped, attributes finite."""
    floor = grid_plane((40, 60), (4, 6), uv_scale=(10, 15), material=0).transformed(
        trs_matrix((0, -0.5, -25)))  # runs from z = +5 (behind the eye) to z = -55
    wall = grid_plane((3, 6), (1, 1), material=2).transformed(
        trs_matrix((1.0, 0.0, 0.0), (0, 0, 90)))  # x = 1 plane through the eye's depth
    tris = [[[-3, 0.5, 3], [3, 0.5, 3], [0, 0.5, -8]],  # a ceiling from behind to ahead
            [[-0.5, -0.3, 1], [0.5, -0.3, 1], [0, 0.4, -3]]]
    return case_scene("hard_near_plane", [floor, wall, triangle_soup(tris)],
                      case_camera((0, 0, 0), (0, 0, -1), near=0.05, far=200),
                      doc=near_plane.__doc__)


def w_near_zero() -> Scene:
    """Vertices at w near 0: on the eye plane (w = 0), 1e-7 in front of and behind it, with a
    near plane of 1e-4.

    Stresses: the division by w (x/w with w ~ 1e-7 reaches 1e7), the clip of edges whose end
    points straddle w = 0, guard-band overflow of the fixed-point snap. Must hold: finite, only
    the in-front parts drawn, no wrap-around of huge snapped coordinates."""
    tris = [[[-1, -1, -1e-7], [1, -1, -1e-7], [0, 1, -2]],
            [[-2, 0.2, 0.0], [2, 0.2, 0.0], [0, 0.6, -3]],
            [[-0.5, -0.6, 1e-7], [0.5, -0.6, -1e-7], [0.0, -0.2, -1.5]],
            [[0.3, 0.3, -1e-4], [0.8, 0.3, -1.00001e-4], [0.5, 0.9, -1e-4]]]  # on the near plane
    return case_scene("hard_w_near_zero", [backdrop(z=-4), triangle_soup(tris)],
                      case_camera((0, 0, 0), (0, 0, -1), near=1e-4, far=50),
                      doc=w_near_zero.__doc__)


def _far(offset: float, scale: float, name: str, doc: str) -> Scene:
    off = np.array([offset, -offset, offset]) if offset else np.zeros(3)
    wall = backdrop(z=-2.0 * scale, size=12.0 * scale)
    wall.positions = wall.positions + off
    s = uv_sphere(0.8 * scale, 8, 16, material=1)
    s.positions = s.positions + off
    cam = look_at(off + (0, 0, 2.5 * scale), off, near=0.1 * scale, far=100.0 * scale)
    lights = case_lights(point=(tuple(off + np.array((1.5, 1.5, 2.5)) * scale), 6.0 * scale ** 2))
    return case_scene(name, [wall, s], cam, lights=lights, doc=doc)


def far_1e5() -> Scene:
    """A sphere before a wall 1e5 units from the origin (scaled x10, camera beside them).

    Stresses: float32 positions whose ulp is 0.008; the camera-relative transform (p - eye
    before the rotation). Must hold: the image matches the same scene at the origin
    (``far_origin``) within the bound, as a matrix carrying the translation would not."""
    return _far(1e5, 10.0, "hard_far_1e5", far_1e5.__doc__)


def far_1e7() -> Scene:
    """The same scene 1e7 units from the origin (scaled x1000: a float32 ulp there is 1 unit).

    Stresses: as far_1e5, at the limit of float32 world coordinates. Must hold: finite, and
    the image matches ``far_origin`` within the bound."""
    return _far(1e7, 1000.0, "hard_far_1e7", far_1e7.__doc__)


def far_origin() -> Scene:
    """The far_* scenes at the origin, unscaled: their comparison image.

    Must hold: finite, error in bound (it is the easy twin of far_1e5 and far_1e7)."""
    return _far(0.0, 1.0, "hard_far_origin", far_origin.__doc__)


def coplanar() -> Scene:
    """Overlapping coplanar quads of different colours (and one submitted twice).

    Stresses: exact depth ties. Must hold: a deterministic winner, the lower triangle index
    (the rasterizer's depth key), in every pipeline and on every rerun."""
    a = grid_plane((2.0, 2.0), material=1).transformed(trs_matrix((-0.4, 0, 0), (90, 0, 0)))
    b = grid_plane((2.0, 2.0), material=2).transformed(trs_matrix((0.4, 0.2, 0), (90, 0, 0)))
    c = grid_plane((2.0, 2.0), material=3).transformed(trs_matrix((-0.4, 0, 0), (90, 0, 0)))
    return case_scene("hard_coplanar", [backdrop(), a, b, c], case_camera(), doc=coplanar.__doc__)


def fov_1() -> Scene:
    """A sphere seen through a 1-degree field of view from 100 units away.

    Stresses: f = 1/tan(fov/2) = 115, tiny pixel footprints (huge barycentric derivatives per
    world unit reversed: duv tiny, texture magnified). Must hold: finite, error in bound."""
    return case_scene("hard_fov_1", [backdrop(), sphere()],
                      case_camera((0, 0, 100.0), (0, 0, 0), fov_y_deg=1.0, near=1.0, far=300.0),
                      doc=fov_1.__doc__)


def fov_170() -> Scene:
    """A sphere and a wall through a 170-degree field of view.

    Stresses: f = 0.087, strong perspective at the image border, large guard-band coordinates.
    Must hold: finite, error in bound."""
    return case_scene("hard_fov_170", [backdrop(z=-1.0, size=80.0, uv_scale=(40, 40)), sphere()],
                      case_camera((0, 0, 1.2), (0, 0, 0), fov_y_deg=170.0, near=0.01, far=100.0),
                      doc=fov_170.__doc__)


def grazing() -> Scene:
    """A textured Blinn-Phong floor seen from 1e-3 above it, so normal . view falls to 1e-5.

    Stresses: grazing-angle shading (n.v ~ 0, half vectors near the tangent plane), extreme
    anisotropic texture footprints. Must hold: finite, error in bound."""
    floor = grid_plane((400, 400), (4, 4), uv_scale=(400, 400), material=0)
    shiny = grid_plane((400, 400), (1, 1), material=1).transformed(trs_matrix((0, 0, -400)))
    return case_scene("hard_grazing", [floor, shiny],
                      case_camera((0, 1e-3, 0), (0, 1e-3, -10), near=1e-4, far=1000.0),
                      lights=case_lights(point=((0.0, 0.5, -30.0), 300.0),
                                         sun=((0.0, 0.02, -1.0), 2.0)),
                      doc=grazing.__doc__)
