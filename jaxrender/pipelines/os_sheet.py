"""Object-space shading, step 2: the virtual shade sheet of every object and its triangle-id map.

Each object has a square power-of-two sheet (``res`` shadels a side) with a MIP chain down to one
8x8 chunk. The virtual address space enumerates every chunk of every level of every object:
virtual chunk id = ``obj_base[o, l] + cy * (res_l / 8) + cx``; shadel ``(x, y)`` of a chunk is
lane ``(y % 8) * 8 + x % 8``. Nothing is stored per virtual chunk but its static description
and the triangle that owns each shadel; colours live in the physical store (os_alloc).

The triangle-id map is rasterized in chart (s, t) space at every level with the shared
rasterizer's rules (``raster_st``: 8-bit snapping, exact integer edge functions, top-left rule;
a NumPy loop because the map is built once per mesh on the host and the jitted rasterizer would
compile once per level size; a test checks it against ``rasterize_clip``): first normally
(texel centres), then conservatively (every texel whose square the triangle touches, into the
texels still empty), then one ring of gutter dilation (so every bilinear tap next to a chart edge
has an owner), and finally every triangle that still owns no shadel claims the texel under its
chart centroid (when that texel's owner keeps another one). At level 0 every triangle then owns
at least one shadel (a triangle of zero chart area included).
"""

from __future__ import annotations

from collections import OrderedDict

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.os_charts import _tri_area2, object_charts, scene_key
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
    world = 0.5 * float(_tri_area2(pos[f]).sum())
    fill = max(0.5 * float(_tri_area2(chart.corner_st).sum()), 1e-6)
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


SUBPIXEL = 256  # 8-bit sub-texel snapping, as the shared rasterizer


def _snap(st: np.ndarray, res: int) -> np.ndarray:
    """Chart coordinates [T, 3, 2] -> fixed-point texel coordinates int64 (x right, y down)."""
    return np.round(st * (res * SUBPIXEL)).astype(np.int64)


def raster_st(st: np.ndarray, res: int, conservative: bool = False, window=None
              ) -> tuple[np.ndarray, np.ndarray]:
    """Rasterize chart triangles st[T, 3, 2] onto a res x res texel grid with the shared
    rasterizer's rules (8-bit snapping, exact integer edge functions, top-left fill rule, ties
    to the lowest triangle index). ``conservative``: a texel is covered when its square
    overlaps the triangle at all (edge functions at the square's most inside corner, plus the
    bounding box: the separating-axis test). Returns (owner int64[res, res] lowest covering
    triangle or -1, hits int32[res, res] covering triangles per texel). ``window`` (x0, y0, w,
    h) in texels: only that part of the grid, as arrays of shape [h, w] (the same values)."""
    x0, y0, w, h = window if window is not None else (0, 0, res, res)
    v = _snap(st, res)
    # Shifted in fixed point (exact): texel (x0, y0) becomes the window's texel (0, 0).
    xs, ys = v[..., 0] - x0 * SUBPIXEL, v[..., 1] - y0 * SUBPIXEL
    area2 = ((xs[:, 1] - xs[:, 0]) * (ys[:, 2] - ys[:, 0])
             - (ys[:, 1] - ys[:, 0]) * (xs[:, 2] - xs[:, 0]))
    half = SUBPIXEL // 2
    pad = half if conservative else 0
    lo_x = np.maximum(-((half + pad - xs.min(1)) // SUBPIXEL), max(-x0, 0))
    hi_x = np.minimum((xs.max(1) + pad - half) // SUBPIXEL, min(w, res - x0) - 1)
    lo_y = np.maximum(-((half + pad - ys.min(1)) // SUBPIXEL), max(-y0, 0))
    hi_y = np.minimum((ys.max(1) + pad - half) // SUBPIXEL, min(h, res - y0) - 1)
    live = (area2 != 0) & (lo_x <= hi_x) & (lo_y <= hi_y)
    # Triangles in batches of similar bounding-box width and height, each batch on an
    # [n, SY, SX] grid of powers of two: a long sliver (xatlas charts of thin boxes) costs its
    # box, not the square around it (measured 2026-11-23: the thin scene's sheet took 66 s
    # with square grids).
    bits_x = _ceil_log2(hi_x - lo_x + 1)
    bits_y = _ceil_log2(hi_y - lo_y + 1)
    big = np.int64(np.iinfo(np.int64).max)
    owner = np.full(w * h, big, np.int64)
    hits = np.zeros(w * h, np.int32)
    bucket = bits_x * 64 + bits_y
    for b in np.unique(bucket[live]):
        sel = np.nonzero(live & (bucket == b))[0]
        sx_, sy_ = 1 << int(b // 64), 1 << int(b % 64)
        step = max(1, (1 << 20) // (sx_ * sy_))
        for start in range(0, sel.size, step):
            _cover(sel[start:start + step], xs, ys, area2, lo_x, lo_y, hi_x, hi_y, sx_, sy_,
                   w, conservative, owner, hits)
    owner = np.where(owner == big, -1, owner).reshape(h, w)
    return owner, hits.reshape(h, w)


def _ceil_log2(n: np.ndarray) -> np.ndarray:
    """Smallest b with 2^b >= n, for n >= 1 (0 where n <= 1)."""
    n = np.maximum(np.asarray(n, np.int64), 1)
    b = np.zeros(n.shape, np.int64)
    while np.any((1 << b) < n):
        b += (1 << b) < n
    return b


def _cover(k, xs, ys, area2, lo_x, lo_y, hi_x, hi_y, size_x, size_y, row, conservative, owner,
           hits):
    half = SUBPIXEL // 2
    px = lo_x[k][:, None, None] + np.arange(size_x)[None, None, :]
    py = lo_y[k][:, None, None] + np.arange(size_y)[None, :, None]
    inside = (px <= hi_x[k][:, None, None]) & (py <= hi_y[k][:, None, None])
    sx, sy = px * SUBPIXEL + half, py * SUBPIXEL + half
    sign = np.where(area2[k] < 0, -1, 1)
    for i in range(3):
        a, b = (i + 1) % 3, (i + 2) % 3
        dx = ((xs[k, b] - xs[k, a]) * sign)[:, None, None]
        dy = ((ys[k, b] - ys[k, a]) * sign)[:, None, None]
        e = dx * (sy - ys[k, a][:, None, None]) - dy * (sx - xs[k, a][:, None, None])
        if conservative:
            inside &= e + (np.abs(dx) + np.abs(dy)) * half >= 0
        else:
            top_left = (dy < 0) | ((dy == 0) & (dx > 0))
            inside &= (e > 0) | ((e == 0) & top_left)
    tri = np.broadcast_to(k[:, None, None], inside.shape)[inside]
    pix = (py * row + px)[inside]
    if pix.size == 0:
        return
    # Lowest triangle per texel, and the count, from one sort of (texel, triangle) keys:
    # ufunc.at (a scatter with repeats) was the slowest step of a sheet build (2026-11-23).
    stride = int(k.max(initial=0)) + 1
    key = np.sort(pix * stride + tri)
    texel = key // stride
    start = np.flatnonzero(np.r_[True, texel[1:] != texel[:-1]])
    t = texel[start]
    owner[t] = np.minimum(owner[t], key[start] - t * stride)
    hits[t] += np.diff(np.r_[start, key.size]).astype(hits.dtype)


def _raster_owner(st: np.ndarray, res: int) -> tuple[np.ndarray, int, int]:
    """Owner map (local triangle index, -1 none) of a res x res grid: texel centres, then the
    conservative pass into the texels still empty, then one ring of gutter dilation, then
    triangles that own no texel claim one. Computed on the chart's texel bounding box plus
    that ring (a thin object's chart can fill a few rows of a large grid): returns the window
    int64[h, w] and its corner (x0, y0); every texel outside it is -1."""
    v = _snap(st, res).reshape(-1, 2)
    lo = np.maximum(v.min(0) // SUBPIXEL - 2, 0)
    hi = np.minimum(v.max(0) // SUBPIXEL + 2, res - 1)
    x0, y0 = int(lo[0]), int(lo[1])
    win = (x0, y0, int(hi[0]) - x0 + 1, int(hi[1]) - y0 + 1)
    own, _ = raster_st(st, res, window=win)
    cons, _ = raster_st(st, res, conservative=True, window=win)
    own = np.where(own < 0, cons, own)
    h, w = own.shape
    pad = np.pad(own, 1, constant_values=-1)
    dil = own.copy()
    for dy, dx in ((0, -1), (0, 1), (-1, 0), (1, 0), (-1, -1), (-1, 1), (1, -1), (1, 1)):
        nb = pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
        dil = np.where(dil < 0, nb, dil)
    return _claim_orphans(dil, st, res, x0, y0), x0, y0


def _claim_orphans(own: np.ndarray, st: np.ndarray, res: int, x0: int = 0, y0: int = 0
                   ) -> np.ndarray:
    """Every triangle owning no texel takes the texel under its centroid (or a corner) when the
    texel's owner keeps at least one other texel. ``own`` is the window of the grid whose
    texel (0, 0) is the grid's (x0, y0); it holds every corner's texel."""
    t = st.shape[0]
    h, w = own.shape
    counts = np.bincount(own[own >= 0], minlength=t)
    for k in np.nonzero(counts == 0)[0]:
        for p in (st[k].mean(0), *st[k]):
            x, y = (np.clip(np.floor(p * res), 0, res - 1)).astype(np.int64)
            x, y = min(max(x - x0, 0), w - 1), min(max(y - y0, 0), h - 1)
            prev = own[y, x]
            if prev < 0 or counts[prev] > 1:
                if prev >= 0:
                    counts[prev] -= 1
                own[y, x] = k
                counts[k] += 1
                break
    return own


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
                own, x0, y0 = _raster_owner(ch.corner_st, rl)
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
