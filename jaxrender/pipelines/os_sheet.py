"""Object-space shading, step 2: the virtual shade sheet of every object and its triangle-id map.

Each object has a square power-of-two sheet (``res`` shadels a side) with a MIP chain down to one
8x8 chunk. The virtual address space enumerates every chunk of every level of every object:
virtual chunk id = ``obj_base[o, l] + cy * (res_l / 8) + cx``; shadel ``(x, y)`` of a chunk is
lane ``(y % 8) * 8 + x % 8``. Nothing is stored per virtual chunk but its static description
and the triangle that owns each shadel; colours live in the physical store (os_alloc).

The triangle-id map is rasterized in chart (s, t) space at every level with the shared
rasterizer's rules (``os_texels.raster_st``: 8-bit snapping, exact integer edge functions,
top-left rule; a NumPy loop because the map is built once per mesh on the host and the jitted
rasterizer would compile once per level size; a test checks it against ``rasterize_clip``):
first normally (texel centres), then conservatively (every texel whose square the triangle
touches, into the texels still empty), then one ring of gutter dilation (so every bilinear tap
next to a chart edge has an owner), and finally every triangle that still owns no shadel claims
the texel under its chart centroid (when that texel's owner keeps another one). At level 0 every
triangle then owns at least one shadel (a triangle of zero chart area included).
"""

from __future__ import annotations

from collections import OrderedDict

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.os_charts import object_charts, scene_key
from jaxrender.pipelines.os_texels import raster_owner, tri_area2
from jaxrender.types import Array, pytree_dataclass, static_field

CHUNK = 8  # shadels per chunk side
LANES = CHUNK * CHUNK
MIN_RES = CHUNK
_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 8


@pytree_dataclass
class ShadeSheet:
    """The static virtual shade sheets of a scene (arrays are device arrays, shapes static).

    corner_st float32[T, 3, 2]: chart coordinates of each triangle corner.
    owner int32[NC * 64]: owning triangle of each virtual shadel (-1: none).
    chunk_obj, chunk_level, chunk_cx, chunk_cy int32[NC]: what each virtual chunk is.
    obj_res int32[O]: level-0 shadels per side; obj_levels int32[O]; obj_base int32[O, L].
    n_chunks, max_levels: static sizes; sources: "own"/"xatlas" per object; level0_shadels.
    """

    corner_st: Array
    owner: Array
    chunk_obj: Array
    chunk_level: Array
    chunk_cx: Array
    chunk_cy: Array
    obj_res: Array
    obj_levels: Array
    obj_base: Array
    n_chunks: int = static_field(default=0)
    max_levels: int = static_field(default=1)
    level0_chunks: int = static_field(default=0)
    sources: tuple = static_field(default=())


def levels_of(res: int) -> int:
    """MIP levels from ``res`` down to one chunk (res >= 8, a power of two)."""
    return int(np.log2(res // CHUNK)) + 1


def _pow2(x: float, lo: int, hi: int) -> int:
    r = 1 << int(np.ceil(np.log2(max(x, 1.0))))
    return int(min(max(r, lo), hi))


def object_resolution(scene, chart, cfg) -> int:
    """Level-0 shadels per side: ``cfg.sheet_resolution`` if set; else the materials' own
    frequency (texture or stripe resolution times the uv extent, so shadels align with texels)
    when the object has one, otherwise ``texel_density`` shadels per world unit over the
    chart's fill. A power of two in [8, max_sheet_resolution]."""
    hi = int(cfg.max_sheet_resolution)
    if cfg.sheet_resolution:
        return _pow2(cfg.sheet_resolution, MIN_RES, hi)
    pos = np.asarray(scene.positions, np.float64)
    f = np.asarray(scene.faces)[chart.tris]
    world = 0.5 * float(tri_area2(pos[f]).sum())
    fill = max(0.5 * float(tri_area2(chart.corner_st).sum()), 1e-6)
    density = cfg.texel_density * np.sqrt(world / fill)
    mats = np.unique(np.asarray(scene.tri_material)[chart.tris])
    m = scene.materials
    ext = chart.uv_extent if chart.source == "own" else 1.0
    natural = 0.0
    for k in mats:
        if scene.effects.procedural and int(np.asarray(m.procedural)[k]) != 0:
            natural = max(natural, float(np.asarray(m.stripe_resolution)[k]) * ext)
        if scene.effects.textures and int(np.asarray(m.texture)[k]) >= 0:
            natural = max(natural, float(scene.textures.resolution) * ext)
    want = natural if natural > 0 else density
    return _pow2(want, MIN_RES, hi)


def _to_chunks(m: np.ndarray) -> np.ndarray:
    """[res, res] -> chunk-major flat [(res/8)^2 * 64]."""
    r = m.shape[0]
    c = r // CHUNK
    return m.reshape(c, CHUNK, c, CHUNK).transpose(0, 2, 1, 3).reshape(-1)


def build_sheet(scene, cfg) -> ShadeSheet:
    """The virtual sheets of ``scene`` (host-side, cached by mesh content and sheet settings)."""
    if isinstance(scene.positions, jax.core.Tracer):
        raise TypeError("object_space: the shade sheet is built on the host from a concrete "
                        "scene; call object_space.prepare(scene, cfg) outside jit")
    key = scene_key(scene, "sheet", cfg.sheet_resolution, cfg.texel_density,
                    cfg.max_sheet_resolution, cfg.xatlas_resolution, cfg.force_xatlas,
                    scene.effects.procedural, scene.effects.textures)
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key]
    charts = object_charts(scene, cfg.xatlas_resolution, cfg.force_xatlas)
    n_tri = int(np.asarray(scene.faces).shape[0])
    corner = np.zeros((n_tri, 3, 2), np.float64)
    res = [object_resolution(scene, ch, cfg) for ch in charts]
    levels = [levels_of(r) for r in res]
    max_l = max(levels, default=1)
    base = np.zeros((len(charts), max_l), np.int64)
    total = sum((r >> lv) ** 2 for r, nl in zip(res, levels) for lv in range(nl))
    owner = np.empty(total, np.int32)  # filled level by level, chunk-major
    c_obj, c_lvl, c_x, c_y = [], [], [], []
    n = 0
    for o, (ch, r, nl) in enumerate(zip(charts, res, levels)):
        corner[ch.tris] = ch.corner_st
        for lv in range(nl):
            rl = r >> lv
            cps = rl // CHUNK
            base[o, lv] = n
            full = np.full((rl, rl), -1, np.int32)
            if ch.tris.size:
                own, x0, y0 = raster_owner(ch.corner_st, rl)
                full[y0:y0 + own.shape[0], x0:x0 + own.shape[1]] = np.where(
                    own >= 0, ch.tris[np.maximum(own, 0)], -1)
            owner[n * LANES:(n + cps * cps) * LANES] = _to_chunks(full)
            cy, cx = np.divmod(np.arange(cps * cps), cps)
            c_obj.append(np.full(cps * cps, o))
            c_lvl.append(np.full(cps * cps, lv))
            c_x.append(cx)
            c_y.append(cy)
            n += cps * cps
        for lv in range(nl, max_l):
            base[o, lv] = base[o, nl - 1]
    i32 = lambda a: jnp.asarray(np.asarray(a, np.int32))
    cat = lambda xs: i32(np.concatenate(xs) if xs else np.zeros(0))
    level0 = sum((r // CHUNK) ** 2 for r in res)
    sheet = ShadeSheet(
        corner_st=jnp.asarray(corner.astype(np.float32)), owner=jnp.asarray(owner),
        chunk_obj=cat(c_obj), chunk_level=cat(c_lvl), chunk_cx=cat(c_x), chunk_cy=cat(c_y),
        obj_res=i32(res), obj_levels=i32(levels), obj_base=i32(base), n_chunks=int(n),
        max_levels=int(max_l), level0_chunks=int(level0),
        sources=tuple(ch.source for ch in charts))
    _CACHE[key] = sheet
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return sheet
