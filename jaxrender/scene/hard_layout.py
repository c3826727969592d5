"""The shared layout of the hard-case scenes: one compile per (pipeline, resolution) serves the
whole catalogue, so every case has ``N_VERTS`` vertices and ``N_FACES`` faces (padded with
zero-area triangles), the same ``N_MATERIALS`` material slots, the same two 64x64 textures (a
checker and a noise image), one directional and one point light, and the same static
``EFFECTS``; and the helpers the cases are built from.
"""

from __future__ import annotations

import dataclasses

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
BACKDROP = Material("backdrop", albedo=(1.0, 1.0, 1.0), texture=0)
OBJECT = Material("object", albedo=(0.6, 0.3, 0.1), specular=(0.4, 0.4, 0.4), shininess=32,
                  brdf="blinn_phong")
SECOND = Material("second", albedo=(0.1, 0.3, 0.8))
NOISE = Material("noise", albedo=(1.0, 1.0, 1.0), texture=1)
MATERIALS = (BACKDROP, OBJECT, SECOND, NOISE)


def case_textures() -> list[np.ndarray]:
    n = TEXTURE_RES
    i = np.arange(n) * 8 // n
    mask = ((i[:, None] + i[None, :]) % 2 == 0)[..., None]
    checker = np.where(mask, [0.8, 0.8, 0.8], [0.15, 0.15, 0.2])
    noise = np.random.default_rng(10).integers(0, 2, (n, n, 3)).astype(np.float64)  # 0 or 1
    one = np.ones((n, n, 1))
    return [np.concatenate([checker, one], -1), np.concatenate([noise, one], -1)]


def case_lights(point=((1.5, 1.5, 2.5), 6.0), sun=((0.3, 0.5, 1.0), 1.5), ambient=0.05):
    return make_lights([sun], [point], ambient=ambient)


def pad_to_layout(parts: list[MeshPart]) -> list[MeshPart]:
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


def case_scene(name: str, parts: list[MeshPart], camera, *, lights=None, doc: str = "",
               materials=MATERIALS) -> Scene:
    del name, doc  # see SCENE_NAME
    return build_scene(pad_to_layout(parts), list(materials), case_textures(),
                       lights or case_lights(), camera,
                       name=SCENE_NAME, description=SCENE_DESCRIPTION, effects=EFFECTS,
                       texture_resolution=TEXTURE_RES)


def backdrop(z=-2.0, size=12.0, material=0, uv_scale=(4.0, 4.0), offset=(0, 0, 0), scale=1.0):
    """A wall facing +Z at depth z (normal towards a camera on +Z)."""
    wall = grid_plane((size, size), (2, 2), uv_scale=uv_scale, material=material)
    return wall.transformed(trs_matrix(np.add((0, 0, z), offset) * scale, (90, 0, 0), scale))


def sphere(r=0.8, centre=(0.0, 0.0, 0.0), material=1, lat=8, lon=16):
    return uv_sphere(r, lat, lon, material=material).transformed(trs_matrix(centre))


def case_camera(eye=(0.0, 0.0, 2.5), target=(0.0, 0.0, 0.0), **kw):
    return look_at(eye, target, **kw)


def triangle_soup(pts, material=1) -> MeshPart:
    """Triangle soup from float[T, 3, 3] corners, normals +Z, uvs from x, y."""
    p = np.asarray(pts, np.float64).reshape(-1, 3)
    f = np.arange(len(p)).reshape(-1, 3)
    nrm = np.tile([0.0, 0.0, 1.0], (len(p), 1))
    return MeshPart(p, f, nrm, p[:, :2] * 0.25, material=material)
