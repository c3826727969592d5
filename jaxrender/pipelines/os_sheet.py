"""Object-space shading, step 2: the virtual shade sheet of every object and its triangle-id map.

Each object has a square power-of-two sheet (``res`` shadels a side) with a MIP chain down to one
8x8 chunk; with ``opaque_only`` (TADS) only the objects with a face that does not blend have
one. The virtual address space enumerates every chunk of every level of every object: virtual
chunk id = ``obj_base[o, l] + cy * (res_l / 8) + cx``; shadel ``(x, y)`` of a chunk is lane
``(y % 8) * 8 + x % 8``. Nothing is stored per virtual chunk but its static description
and the triangle that owns each shadel; colours live in the physical store (os_alloc).

The triangle-id map is rasterized in chart (s, t) space at every level with the shared
rasterizer's rules (``os_texels.raster_st``: 8-bit snapping, exact integer edge functions,
top-left rule; a NumPy loop because the map is built once per mesh on the host and the jitted
rasterizer would compile once per level size; a test checks it against ``rasterize_clip``):
first normally (texel centres), then conservatively (every texel whose square the triangle
touches, into the texels still empty), then one ring of gutter dilation (so every bilinear tap
next to a chart edge has an owner), and finally every triangle that still owns no shadel claims
the texel under its chart centroid (when that texel's owner keeps another one). At level 0 every
triangle of an object with a sheet then owns at least one shadel (a triangle of zero chart area
included).
"""

from __future__ import annotations

from collections import OrderedDict

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.os_charts import object_charts, scene_key
from jaxrender.pipelines.os_texels import raster_owner, tri_area2
from jaxrender.pipelines.visibility import is_transparent
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
    n_chunks, max_levels: static sizes; sources: "own"/"xatlas" per object, "none" for an
    object without a sheet (obj_res 0, obj_levels 0: ``build_sheet``'s ``opaque_only``);
    level0_chunks; spare_chunks: chunks of no object (the one unowned chunk of a sheet where
    no object has one), not part of any sheet's memory.
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
    spare_chunks: int = static_field(default=0)
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


def sheet_objects(scene, opaque_only: bool) -> np.ndarray:
    """bool[O]: the objects that get a sheet: every one, or with ``opaque_only`` those with at
    least one face that does not blend (``visibility.is_transparent``). A pipeline that draws
    blended faces in the forward transparent pass (TADS) never shades them into a sheet, so a
    blended-only object's sheet would be memory counted and packed for nothing."""
    obj = np.asarray(scene.tri_object, np.int64)
    n_obj = int(obj.max()) + 1 if obj.size else 0
    if not opaque_only:
        return np.ones(n_obj, bool)
    opaque = ~np.asarray(is_transparent(scene, jnp.arange(obj.size, dtype=jnp.int32)))
    return np.bincount(obj[opaque], minlength=n_obj) > 0


def _chunks(charts, res: list[int], levels: list[int], max_l: int):
    """The chunk-major owner map and the per-chunk and per-object arrays of the sheets:
    (owner int32[NC * 64], base int64[O, L], [chunk_obj, chunk_level, chunk_cx, chunk_cy]).
    An object without a sheet (res 0) has no chunk; its ``base`` row is 0 (never read)."""
    base = np.zeros((len(charts), max_l), np.int64)
    total = sum((r >> lv) ** 2 for r, nl in zip(res, levels) for lv in range(nl))
    owner = np.empty(total, np.int32)  # filled level by level, chunk-major
    cols = [[], [], [], []]  # chunk_obj, chunk_level, chunk_cx, chunk_cy
    n = 0
    for o, (ch, r, nl) in enumerate(zip(charts, res, levels)):
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
            for col, v in zip(cols, (np.full(cps * cps, o), np.full(cps * cps, lv), cx, cy)):
                col.append(v)
            n += cps * cps
        if nl:
            base[o, nl:] = base[o, nl - 1]
    return owner, base, [np.concatenate(c) if c else np.zeros(0, np.int64) for c in cols]


def build_sheet(scene, cfg, opaque_only: bool = False) -> ShadeSheet:
    """The virtual sheets of ``scene`` (host-side, cached by mesh content and sheet settings).
    With ``opaque_only`` an object whose faces all blend gets no sheet (``sheet_objects``): no
    chart, resolution 0, no level and no chunk."""
    if isinstance(scene.positions, jax.core.Tracer):
        raise TypeError("object_space: the shade sheet is built on the host from a concrete "
                        "scene; call object_space.prepare(scene, cfg) outside jit")
    keep = sheet_objects(scene, opaque_only)
    # The objects left out are part of the key: they depend on the materials' blend modes,
    # which scene_key does not hash.
    key = scene_key(scene, "sheet", cfg.sheet_resolution, cfg.texel_density,
                    cfg.max_sheet_resolution, cfg.xatlas_resolution, cfg.force_xatlas,
                    scene.effects.procedural, scene.effects.textures,
                    tuple(np.flatnonzero(~keep).tolist()))
    if key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key]
    charts = object_charts(scene, cfg.xatlas_resolution, cfg.force_xatlas, np.flatnonzero(keep))
    corner = np.zeros((int(np.asarray(scene.faces).shape[0]), 3, 2), np.float64)
    for ch in charts:
        corner[ch.tris] = ch.corner_st
    res = [object_resolution(scene, ch, cfg) if k else 0 for ch, k in zip(charts, keep)]
    levels = [levels_of(r) if r else 0 for r in res]
    max_l = max([1, *levels])
    owner, base, cols = _chunks(charts, res, levels, max_l)
    spare = 0
    if owner.size == 0:  # no object has a sheet: one unowned chunk, as JAX cannot gather
        spare = 1        # from an empty array (never read: no tap reaches it)
        owner = np.full(LANES, -1, np.int32)
        cols = [np.array([-1]), np.zeros(1), np.zeros(1), np.zeros(1)]
    i32 = lambda a: jnp.asarray(np.asarray(a, np.int32))  # noqa: E731
    sheet = ShadeSheet(
        corner_st=jnp.asarray(corner.astype(np.float32)), owner=jnp.asarray(owner),
        chunk_obj=i32(cols[0]), chunk_level=i32(cols[1]), chunk_cx=i32(cols[2]),
        chunk_cy=i32(cols[3]), obj_res=i32(res), obj_levels=i32(levels), obj_base=i32(base),
        n_chunks=int(owner.size // LANES), max_levels=int(max_l),
        level0_chunks=int(sum((r // CHUNK) ** 2 for r in res)), spare_chunks=spare,
        sources=tuple(ch.source if k else "none" for ch, k in zip(charts, keep)))
    _CACHE[key] = sheet
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return sheet
