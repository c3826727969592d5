"""Scenes for the forward / deferred / visbuffer tests: axis-aligned rectangles and triangles
given in window (pixel) coordinates, so that coverage can be worked out by hand.

The camera sits at the origin looking down -Z with a 90 degree vertical field of view; a
window point (x, y) at view distance d maps to world (( 2x/W - 1) * aspect * d, (1 - 2y/H) d, -d).
Every scene takes the shapes, materials, lights and effect flags of the small ``foliage`` scene
(``FOLIAGE_CARDS`` cards; material 0 the alpha-tested leaf, 1 the opaque ground), padded with
degenerate triangles, so that each pipeline compiles once per configuration for all the tests,
foliage included (compiling is the slow part on a CPU).
"""

from __future__ import annotations

import dataclasses
import functools

import jax.numpy as jnp
import numpy as np

from jaxrender.scene import MeshPart, look_at
from jaxrender.scene.builtin import foliage

W, H = 32, 24
FOLIAGE_CARDS = 30
LEAF, GROUND = 0, 1


@functools.lru_cache(maxsize=1)
def foliage_scene():
    return foliage(n_cards=FOLIAGE_CARDS)


def window_to_world(xy, d, width=W, height=H):
    xy = np.asarray(xy, np.float64)
    aspect = width / height
    x = (2.0 * xy[:, 0] / width - 1.0) * aspect * d
    y = (1.0 - 2.0 * xy[:, 1] / height) * d
    return np.stack([x, y, np.full_like(x, -d)], 1)


def tri_part(corners, d, material=GROUND, width=W, height=H) -> MeshPart:
    pos = window_to_world(corners, d, width, height)
    return MeshPart(pos, np.array([[0, 1, 2]]), normals=np.tile([0.0, 0.0, 1.0], (3, 1)),
                    material=material)


def rect_part(x0, y0, x1, y1, d, material=GROUND, width=W, height=H, tilt=0.0) -> MeshPart:
    """Pixels [x0, x1) x [y0, y1) at view distance d; ``tilt`` bends the vertex normals apart
    so that the shading varies across the rectangle."""
    pos = window_to_world([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], d, width, height)
    nrm = np.array([[-tilt, tilt, 1.0], [tilt, tilt, 1.0], [tilt, -tilt, 1.0], [-tilt, -tilt, 1.0]])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return MeshPart(pos, np.array([[0, 2, 1], [0, 3, 2]]), normals=nrm, material=material)


def make_scene(parts):
    """The parts (world space, drawn in list order) in a scene shaped like ``foliage_scene()``,
    seen from a camera at the origin looking down -Z with a 90 degree field of view."""
    tmpl = foliage_scene()
    nv, nt = tmpl.positions.shape[0], tmpl.faces.shape[0]
    pos, nrm, faces, mat, obj = [], [], [], [], []
    base = 0
    for k, p in enumerate(parts):
        pos.append(p.positions)
        nrm.append(p.normals)
        faces.append(p.faces + base)
        mat.append(np.broadcast_to(np.asarray(p.material), (len(p.faces),)))
        obj.append(np.full(len(p.faces), k))
        base += len(p.positions)
    pos, nrm, faces = np.concatenate(pos), np.concatenate(nrm), np.concatenate(faces)
    mat, obj = np.concatenate(mat), np.concatenate(obj)
    assert len(pos) <= nv and len(faces) <= nt
    pad_v, pad_t = nv - len(pos), nt - len(faces)
    pos = np.concatenate([pos, np.zeros((pad_v, 3))])
    nrm = np.concatenate([nrm, np.tile([0.0, 0.0, 1.0], (pad_v, 1))])
    faces = np.concatenate([faces, np.zeros((pad_t, 3), np.int64)])  # degenerate: never covered
    mat = np.concatenate([mat, np.full(pad_t, GROUND)])
    obj = np.concatenate([obj, np.full(pad_t, len(parts))])
    f32 = lambda a: jnp.asarray(np.asarray(a, np.float32))  # noqa: E731
    i32 = lambda a: jnp.asarray(np.asarray(a, np.int32))  # noqa: E731
    tangents = np.tile([1.0, 0.0, 0.0, 1.0], (nv, 1))
    cam = look_at((0, 0, 0), (0, 0, -1), fov_y_deg=90.0, near=0.5, far=50.0)
    return dataclasses.replace(
        tmpl, positions=f32(pos), normals=f32(nrm), uvs=f32(np.zeros((nv, 2))),
        tangents=f32(tangents), velocity=f32(np.zeros((nv, 3))), faces=i32(faces),
        tri_material=i32(mat), tri_object=i32(obj),
        bounds=f32(np.stack([pos.min(0), pos.max(0)])), camera=cam)
