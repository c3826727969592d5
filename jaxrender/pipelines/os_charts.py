"""Object-space shading, step 1: a unique UV chart per object (mesh) for its shade sheet.

Each object (``scene.tri_object``) gets chart coordinates per triangle corner in [0, 1]^2 with
(s right, t down the sheet). The object's own UVs are used when they are unique: every uv
triangle of non-zero world area has non-zero uv area, and no two uv triangles overlap (checked
exactly with the watertight fill rules: no texel centre of a 256^2 grid is covered twice).
They are fitted into the unit square with one uniform scale (tiling uvs such as a floor with
uv_scale 3 are fine). Otherwise xatlas generates charts (padding 2 texels). Results are cached
per object by a hash of the mesh content, so a camera move never recomputes them.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from jaxrender.pipelines.os_texels import flattened, raster_st, tri_area2

OVERLAP_GRID = 256  # texels per side of the uniqueness test
XATLAS_PADDING = 2  # texels between charts at level 0
_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 16


@dataclass(frozen=True)
class ObjectChart:
    """Chart of one object: corner_st float64[T_o, 3, 2] in [0, 1]^2 for the object's
    triangles ``tris`` int64[T_o] (scene triangle ids); ``source`` "own" or "xatlas";
    ``uv_extent``: the largest side of the own-uv bounding box (texture repeats across it)."""

    tris: np.ndarray
    corner_st: np.ndarray
    source: str
    uv_extent: float


def _fit_unit(uv: np.ndarray, margin: float) -> tuple[np.ndarray, float]:
    """uv[T, 3, 2] -> chart coordinates in [margin, 1 - margin]^2 (uniform scale, t down)."""
    lo, hi = uv.reshape(-1, 2).min(0), uv.reshape(-1, 2).max(0)
    ext = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-12))
    st = (uv - lo) / ext * (1.0 - 2.0 * margin) + margin
    st[..., 1] = 1.0 - st[..., 1]  # uv v up -> sheet rows down
    return st, ext


def own_uvs_unique(corner_st: np.ndarray, world_area2: np.ndarray) -> bool:
    """True when no uv triangle is degenerate (unless its world area is) and none overlap."""
    uv_area2 = tri_area2(corner_st)
    if np.any(flattened(uv_area2, world_area2)):
        return False
    if 0.5 * uv_area2.sum() > 1.0 + 1e-6:  # more uv area than the unit square: overlap for sure
        return False
    _, hits = raster_st(corner_st, OVERLAP_GRID)
    return bool(hits.max(initial=0) <= 1)


def xatlas_chart(positions: np.ndarray, faces: np.ndarray, resolution: int) -> np.ndarray:
    """xatlas charts of one mesh -> corner_st float64[T, 3, 2] in [0, 1]^2."""
    import xatlas

    used, local = np.unique(faces.reshape(-1), return_inverse=True)
    atlas = xatlas.Atlas()
    atlas.add_mesh(positions[used].astype(np.float32), local.reshape(-1, 3).astype(np.uint32))
    po = xatlas.PackOptions()
    po.padding = XATLAS_PADDING
    po.resolution = int(resolution)
    po.bilinear = True
    atlas.generate(xatlas.ChartOptions(), po)
    _vmap, idx, uv = atlas[0]
    size = np.array([atlas.width, atlas.height], np.float64)
    st = uv.astype(np.float64)[idx.astype(np.int64)] * size / size.max()
    if st.shape[0] != faces.shape[0]:  # xatlas dropped faces (degenerate): place them at 0
        raise ValueError("xatlas returned a different number of faces")
    return st


def scene_key(scene, *extra) -> str:
    h = hashlib.sha1()
    for a in (scene.positions, scene.uvs, scene.faces, scene.tri_object, scene.tri_material):
        a = np.ascontiguousarray(np.asarray(a))
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(repr(extra).encode())
    return h.hexdigest()


def _chart(pos, uvs, faces, tris, xatlas_resolution, force_xatlas) -> ObjectChart:
    """The chart of one object's triangles ``tris`` (non-empty)."""
    f = faces[tris]
    own, ext = _fit_unit(uvs[f], margin=0.0)
    if not force_xatlas and own_uvs_unique(own, tri_area2(pos[f])):
        return ObjectChart(tris, own, "own", ext)
    return ObjectChart(tris, xatlas_chart(pos, f, xatlas_resolution), "xatlas", ext)


def object_charts(scene, xatlas_resolution: int = 1024, force_xatlas: bool = False,
                  objects=None) -> list[ObjectChart]:
    """One ObjectChart per object id 0 .. max(tri_object) (cached by mesh content). Only the
    objects ``objects`` (ids; None: all) are charted; any other one gets an empty chart (no
    triangles): TADS does not chart blended-only objects. An object's chart depends on its
    own triangles alone, so charts are cached per object and shared between such subsets."""
    key = scene_key(scene, "charts", xatlas_resolution, force_xatlas)
    done = _CACHE.setdefault(key, {})
    _CACHE.move_to_end(key)
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    pos = np.asarray(scene.positions, np.float64)
    uvs = np.asarray(scene.uvs, np.float64)
    faces = np.asarray(scene.faces, np.int64)
    obj = np.asarray(scene.tri_object, np.int64)
    n_obj = int(obj.max()) + 1 if obj.size else 0
    wanted = set(range(n_obj)) if objects is None else {int(o) for o in objects}
    empty = ObjectChart(np.zeros(0, np.int64), np.zeros((0, 3, 2)), "own", 1.0)
    out = []
    for o in range(n_obj):
        tris = np.nonzero(obj == o)[0]
        if o not in wanted or not tris.size:
            out.append(empty)
            continue
        if o not in done:
            done[o] = _chart(pos, uvs, faces, tris, xatlas_resolution, force_xatlas)
        out.append(done[o])
    return out
