"""The hard-case catalogue (issue 10): scenes built to break a renderer's numerics.

Every case is a generator ``fn(**size_params) -> Scene`` (default camera included) whose
docstring says what it stresses and what must hold, registered with its error bound: the
largest display-referred RMSE (``metrics.to_display``, then RMSE) any pipeline may have against
the reference pipeline at the case's resolution (``HardCase.bound``). Beyond the bound, every
case must give, in every pipeline: no NaN or Inf in the image, the counts or the metrics, and a
bitwise-identical image on a rerun (CPU).

All scenes share one layout so that one compile per (pipeline, resolution) serves the whole
catalogue: ``N_VERTS`` vertices and ``N_FACES`` faces (padded with zero-area triangles), the
same ``N_MATERIALS`` material slots, the same two 64x64 textures (a checker and a noise image),
one directional and one point light, and the same static ``EFFECTS``. The camera is traced, so
fov 1 and fov 170 degrees and eyes at 1e7 do not recompile either.

Cases not expressible as scenes: the metric inputs (constant, black, identical, HDR 1e4) are in
``METRIC_CASES``; the rasterizer's own random-triangle invariants are property tests
(tests/hard_cases/test_hard_raster_props.py), and tests/raster/test_robust.py already pins the
raster-only hard cases (near plane, far coordinates, slivers, ties, non-finite vertices).

Names are ``hard_<case>``, as a study names them once the scene loader knows them (see
``HARD_SCENES``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from jaxrender.scene.camera import look_at
from jaxrender.scene.effects import BLINN_PHONG, LAMBERT, Effects
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import MeshPart, complete, grid_plane, trs_matrix, uv_sphere
from jaxrender.scene.scene import Scene, build_scene

N_VERTS, N_FACES, N_MATERIALS = 2048, 1024, 4
TEXTURE_RES = 64
EFFECTS = Effects(textures=True, specular=True, brdfs=(LAMBERT, BLINN_PHONG))
RESOLUTION = (24, 16)  # the common (width, height) of the catalogue

# material slots: 0 backdrop (checker texture), 1 object (Blinn-Phong), 2 second colour,
# 3 noise-textured
_BACKDROP = Material("backdrop", albedo=(1.0, 1.0, 1.0), texture=0)
_OBJECT = Material("object", albedo=(0.6, 0.3, 0.1), specular=(0.4, 0.4, 0.4), shininess=32,
                   brdf="blinn_phong")
_SECOND = Material("second", albedo=(0.1, 0.3, 0.8))
_NOISE = Material("noise", albedo=(1.0, 1.0, 1.0), texture=1)
_MATERIALS = (_BACKDROP, _OBJECT, _SECOND, _NOISE)


def _textures() -> list[np.ndarray]:
    n = TEXTURE_RES
    i = np.arange(n) * 8 // n
    mask = ((i[:, None] + i[None, :]) % 2 == 0)[..., None]
    checker = np.where(mask, [0.8, 0.8, 0.8], [0.15, 0.15, 0.2])
    noise = np.random.default_rng(10).integers(0, 2, (n, n, 3)).astype(np.float64)  # 0 or 1
    one = np.ones((n, n, 1))
    return [np.concatenate([checker, one], -1), np.concatenate([noise, one], -1)]


def _lights(point=((1.5, 1.5, 2.5), 6.0), sun=((0.3, 0.5, 1.0), 1.5), ambient=0.05):
    return make_lights([sun], [point], ambient=ambient)


def _pad(parts: list[MeshPart]) -> list[MeshPart]:
    """Pad the last part to N_VERTS / N_FACES with zero-area faces on its first vertex (they
    can never cover a sample), so every case has the same array shapes."""
    nv = sum(len(p.positions) for p in parts)
    nf = sum(len(p.faces) for p in parts)
    if nv > N_VERTS or nf > N_FACES:
        raise ValueError(f"hard case too large: {nv} vertices, {nf} faces "
                         f"(layout {N_VERTS}, {N_FACES})")
    last = parts[-1]
    n_last = len(last.positions)
    pos = np.concatenate([last.positions, np.repeat(last.positions[:1], N_VERTS - nv, 0)])
    pad_f = np.zeros((N_FACES - nf, 3), np.int64)
    mat = last.material
    if not np.isscalar(mat):
        mat = np.concatenate([np.asarray(mat), np.full(len(pad_f), np.asarray(mat)[0])])

    def grow(a, width):
        if a is None:
            return None
        extra = np.zeros((N_VERTS - nv, width))
        if width == 3 and a is last.normals:  # a valid unit normal for the padding
            extra[:, 2] = 1.0
        return np.concatenate([np.asarray(a, np.float64).reshape(n_last, width), extra])

    padded = dataclasses.replace(
        last, positions=pos, faces=np.concatenate([np.asarray(last.faces), pad_f]),
        normals=grow(last.normals, 3), uvs=grow(last.uvs, 2), material=mat,
        tangents=None)
    if last.normals is None:  # the normals of the real faces only
        real = complete(dataclasses.replace(last, tangents=None))
        padded = dataclasses.replace(padded, normals=grow(real.normals, 3), uvs=grow(real.uvs, 2))
    return parts[:-1] + [padded]


# Scene.name and Scene.description are static (hashable metadata): were they the case names,
# every case would compile every pipeline anew. They are one string; ``CASES`` has the names.
SCENE_NAME = "hard_cases"
SCENE_DESCRIPTION = "a hard case of jaxrender.scene.hard_cases"


def _scene(name: str, parts: list[MeshPart], camera, *, lights=None, doc: str = "",
           materials=_MATERIALS) -> Scene:
    del name, doc  # see SCENE_NAME
    return build_scene(_pad(parts), list(materials), _textures(), lights or _lights(), camera,
                       name=SCENE_NAME, description=SCENE_DESCRIPTION, effects=EFFECTS,
                       texture_resolution=TEXTURE_RES)


def _backdrop(z=-2.0, size=12.0, material=0, uv_scale=(4.0, 4.0), offset=(0, 0, 0), scale=1.0):
    """A wall facing +Z at depth z (normal towards a camera on +Z)."""
    wall = grid_plane((size, size), (2, 2), uv_scale=uv_scale, material=material)
    return wall.transformed(trs_matrix(np.add((0, 0, z), offset) * scale, (90, 0, 0), scale))


def _sphere(r=0.8, centre=(0.0, 0.0, 0.0), material=1, lat=8, lon=16):
    return uv_sphere(r, lat, lon, material=material).transformed(trs_matrix(centre))


def _camera(eye=(0.0, 0.0, 2.5), target=(0.0, 0.0, 0.0), **kw):
    return look_at(eye, target, **kw)


def _tris(pts, material=1) -> MeshPart:
    """Triangle soup from float[T, 3, 3] corners, normals +Z, uvs from x, y."""
    p = np.asarray(pts, np.float64).reshape(-1, 3)
    f = np.arange(len(p)).reshape(-1, 3)
    nrm = np.tile([0.0, 0.0, 1.0], (len(p), 1))
    return MeshPart(p, f, nrm, p[:, :2] * 0.25, material=material)


# ------------------------------------------------------------------ geometry


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
    return _scene("hard_degenerate", [_backdrop(), _tris(tris)], _camera(),
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
    return _scene("hard_sliver", [_backdrop(), fan, _tris(free, material=2)], _camera(),
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
    return _scene("hard_subpixel", [_backdrop(), _tris(tris)], _camera(), doc=subpixel.__doc__)


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
    return _scene("hard_near_plane", [floor, wall, _tris(tris)],
                  _camera((0, 0, 0), (0, 0, -1), near=0.05, far=200), doc=near_plane.__doc__)


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
    return _scene("hard_w_near_zero", [_backdrop(z=-4), _tris(tris)],
                  _camera((0, 0, 0), (0, 0, -1), near=1e-4, far=50), doc=w_near_zero.__doc__)


def _far(offset: float, scale: float, name: str, doc: str) -> Scene:
    off = np.array([offset, -offset, offset]) if offset else np.zeros(3)
    wall = _backdrop(z=-2.0 * scale, size=12.0 * scale)
    wall.positions = wall.positions + off
    s = uv_sphere(0.8 * scale, 8, 16, material=1)
    s.positions = s.positions + off
    cam = look_at(off + (0, 0, 2.5 * scale), off, near=0.1 * scale, far=100.0 * scale)
    lights = _lights(point=(tuple(off + np.array((1.5, 1.5, 2.5)) * scale), 6.0 * scale ** 2))
    return _scene(name, [wall, s], cam, lights=lights, doc=doc)


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
    return _scene("hard_coplanar", [_backdrop(), a, b, c], _camera(), doc=coplanar.__doc__)


def fov_1() -> Scene:
    """A sphere seen through a 1-degree field of view from 100 units away.

    Stresses: f = 1/tan(fov/2) = 115, tiny pixel footprints (huge barycentric derivatives per
    world unit reversed: duv tiny, texture magnified). Must hold: finite, error in bound."""
    return _scene("hard_fov_1", [_backdrop(), _sphere()],
                  _camera((0, 0, 100.0), (0, 0, 0), fov_y_deg=1.0, near=1.0, far=300.0),
                  doc=fov_1.__doc__)


def fov_170() -> Scene:
    """A sphere and a wall through a 170-degree field of view.

    Stresses: f = 0.087, strong perspective at the image border, large guard-band coordinates.
    Must hold: finite, error in bound."""
    return _scene("hard_fov_170", [_backdrop(z=-1.0, size=80.0, uv_scale=(40, 40)), _sphere()],
                  _camera((0, 0, 1.2), (0, 0, 0), fov_y_deg=170.0, near=0.01, far=100.0),
                  doc=fov_170.__doc__)


def grazing() -> Scene:
    """A textured Blinn-Phong floor seen from 1e-3 above it, so normal . view falls to 1e-5.

    Stresses: grazing-angle shading (n.v ~ 0, half vectors near the tangent plane), extreme
    anisotropic texture footprints. Must hold: finite, error in bound."""
    floor = grid_plane((400, 400), (4, 4), uv_scale=(400, 400), material=0)
    shiny = grid_plane((400, 400), (1, 1), material=1).transformed(trs_matrix((0, 0, -400)))
    return _scene("hard_grazing", [floor, shiny],
                  _camera((0, 1e-3, 0), (0, 1e-3, -10), near=1e-4, far=1000.0),
                  lights=_lights(point=((0.0, 0.5, -30.0), 300.0), sun=((0.0, 0.02, -1.0), 2.0)),
                  doc=grazing.__doc__)


def _phong(exponent: float, name: str, doc: str) -> Scene:
    mat = dataclasses.replace(_OBJECT, shininess=float(exponent))
    return _scene(name, [_backdrop(), _sphere(0.9, lat=16, lon=24)], _camera(),
                  lights=_lights(point=((0.0, 0.0, 2.5), 8.0)), doc=doc,
                  materials=(_BACKDROP, mat, _SECOND, _NOISE))


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
    s = _sphere(0.8, (0.3, 0.0, 0.0))
    k = np.arange(len(s.normals)) % 4
    scale = np.select([k == 0, k == 1, k == 2], [0.0, 1e-30, 1e15],
                      np.random.default_rng(4).uniform(0.1, 10.0, len(k)))
    s.normals = s.normals * scale[:, None]
    wall = _backdrop()
    wall.normals = wall.normals * 7.5
    return _scene("hard_bad_normals", [wall, s], _camera(), doc=bad_normals.__doc__)


def zero_area_uv() -> Scene:
    """Textured surfaces whose UV charts have zero area: a wall with every uv equal, a sphere
    whose uvs are collinear.

    Stresses: texture derivatives of 0 (LOD = log2(0)), tangent frames from a singular uv
    Jacobian, object-space charts of zero area. Must hold: finite, error in bound."""
    wall = _backdrop()
    wall.uvs = np.full_like(wall.uvs, 0.3)
    s = _sphere(0.8, material=3)
    s.uvs = np.stack([s.uvs[:, 0], s.uvs[:, 0]], 1)  # on the line u = v
    return _scene("hard_zero_area_uv", [wall, s], _camera(), doc=zero_area_uv.__doc__)


def minify() -> Scene:
    """A noise-textured floor to the horizon with 1e4 texture repeats (extreme minification:
    thousands of texels per pixel, the coarsest MIP levels and beyond).

    Must hold: finite, colours tend to the texture mean, error in bound."""
    floor = grid_plane((1000, 1000), (4, 4), uv_scale=(1e4, 1e4), material=3)
    return _scene("hard_minify", [floor],
                  _camera((0, 1.0, 0), (0, 0.0, -8), near=0.05, far=2000.0),
                  doc=minify.__doc__)


def magnify() -> Scene:
    """A checker wall seen from 1e-3 away with uvs spanning 1e-4 (one texel fills the screen
    thousands of times over: LOD far below 0).

    Must hold: finite, the magnification filter clamps at level 0, error in bound."""
    wall = _backdrop(z=-1e-3, size=0.1, uv_scale=(1e-4, 1e-4))
    return _scene("hard_magnify", [wall], _camera((0, 0, 0), (0, 0, -1), near=1e-4, far=1.0),
                  doc=magnify.__doc__)


def flat() -> Scene:
    """One untextured Lambert wall filling the view, lit by a directional light only: every
    pixel has the same colour (DACS: all neighbours equal, variance exactly 0).

    Must hold: every pipeline's image is that constant (within float rounding), so error 0."""
    wall = _backdrop(material=2)
    return _scene("hard_flat", [wall], _camera(),
                  lights=_lights(point=((0, 0, 2.5), 0.0), sun=((0.0, 0.0, 1.0), 1.5),
                                 ambient=0.0),
                  doc=flat.__doc__)


def noise() -> Scene:
    """A wall with a binary white-noise texture magnified to about 2 pixels per texel, so the
    MIP filter cannot average it away (DACS: neighbours dissimilar nearly everywhere, so it must
    fall back to shading nearly every pixel rather than interpolate noise).

    Must hold: finite, error in bound."""
    wall = _backdrop(material=3, uv_scale=(0.5, 0.5))
    return _scene("hard_noise", [wall], _camera(), doc=noise.__doc__)


def empty() -> Scene:
    """Geometry only behind the camera: nothing is visible.

    Stresses: empty work lists (zero chunks), empty coverage, metrics of an all-background
    image. Must hold: the image is background (0) and shading counts are 0."""
    return _scene("hard_empty", [_backdrop(z=5.0), _sphere(centre=(0, 0, 4.0))], _camera(),
                  doc=empty.__doc__)


def tiny_image() -> Scene:
    """The reference sphere-and-wall scene for degenerate image sizes: 1 pixel wide (1x16) and
    4096 x 1 (``HardCase.resolutions``).

    Stresses: pixel blocks (quads, 4x4 DACS blocks, 8x8 chunks) cut by the image border, an
    aspect of 1/16 and of 4096. Must hold: finite, error in bound."""
    return _scene("hard_tiny_image", [_backdrop(), _sphere()], _camera(), doc=tiny_image.__doc__)


# ------------------------------------------------------------------ the catalogue


@dataclass(frozen=True)
class HardCase:
    """name: ``hard_<case>``; build: the generator; bound: the largest display RMSE against the
    reference any pipeline may have; resolutions: the (width, height) it is rendered at;
    constant: the image must equal one colour everywhere (within 1e-6) in every pipeline;
    empty: nothing is visible (image 0, no shading)."""

    name: str
    build: Callable[..., Scene]
    bound: float
    resolutions: tuple = (RESOLUTION,)
    constant: bool = False
    empty: bool = False

    @property
    def doc(self) -> str:
        return (self.build.__doc__ or "").strip()


def _c(fn, bound, **kw) -> HardCase:
    return HardCase(f"hard_{fn.__name__}", fn, bound, **kw)


# Bounds: the worst pipeline measured at 24x16 against the reference at k = 4 (forward,
# deferred, visbuffer, checkerboard, dacs, object_space; python benchmarks/bench_hard_cases.py,
# 2026-11-22, CPU) times 1.5, rounded up. The 1-bit-exact cases (flat, empty) state their
# exact expectation. noise measured after (worst: dacs 0.155); tiny_image is provisional.
CASES: dict[str, HardCase] = {c.name: c for c in (
    _c(degenerate, 0.15),
    _c(sliver, 0.14),
    _c(subpixel, 0.15),
    _c(near_plane, 0.09),
    _c(w_near_zero, 0.1),
    _c(far_1e5, 0.15),
    _c(far_1e7, 0.15),
    _c(far_origin, 0.15),
    _c(coplanar, 0.19),
    _c(fov_1, 0.13),
    _c(fov_170, 0.011),
    _c(grazing, 0.025),
    _c(phong_1e4, 0.14),
    _c(phong_1e6, 0.14),
    _c(bad_normals, 0.14),
    _c(zero_area_uv, 0.04),
    _c(minify, 0.02),
    _c(magnify, 1e-05),
    _c(flat, 1e-6, constant=True),
    _c(noise, 0.24),
    _c(empty, 0.0, empty=True),
    _c(tiny_image, 0.20, resolutions=((1, 16), (4096, 1))),
)}

# The scene builders by name, for the scene loader and the study (size parameters as keywords).
HARD_SCENES: dict[str, Callable[..., Scene]] = {n: c.build for n, c in CASES.items()}


def hard_case_scene(name: str, **size_params) -> Scene:
    if name not in CASES:
        raise KeyError(f"unknown hard case {name!r}; cases: {', '.join(CASES)}")
    return CASES[name].build(**size_params)


def list_hard_cases() -> list[tuple[str, str]]:
    return [(n, c.doc.splitlines()[0]) for n, c in CASES.items()]


# ------------------------------------------------------------------ metric inputs

def metric_cases(shape=(16, 16, 3)) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(test, reference) linear image pairs that stress the metrics: constant (two different
    constants), black vs black, identical noise, HDR values of 1e4 against 1e4 +- noise.
    Must hold: no NaN anywhere; PSNR may be +inf only where the images are equal."""
    rng = np.random.default_rng(5)
    a = rng.uniform(0, 1, shape)
    return {
        "constant": (np.full(shape, 0.2), np.full(shape, 0.7)),
        "black": (np.zeros(shape), np.zeros(shape)),
        "identical": (a, a.copy()),
        "hdr_1e4": (1e4 * (1 + 0.1 * a), np.full(shape, 1e4)),
        "hdr_vs_black": (np.full(shape, 1e4), np.zeros(shape)),
    }
