"""Object-space shading: chart triangles rasterized onto texel grids on the host (NumPy), with
the shared rasterizer's rules: 8-bit snapping, exact integer edge functions, the top-left fill
rule, ties to the lowest triangle index. Used for the uniqueness test of an object's own UVs
(``os_charts``) and the triangle-id maps of the shade sheets (``os_sheet``).
"""

from __future__ import annotations

import numpy as np

def tri_area2(p: np.ndarray) -> np.ndarray:
    """Twice the area of triangles p[T, 3, D] (D = 2 or 3)."""
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    if p.shape[-1] == 2:
        return np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return np.linalg.norm(np.cross(e1, e2), axis=-1)


def flattened(chart_area2: np.ndarray, world_area2: np.ndarray) -> np.ndarray:
    """bool[T]: the triangles of one object that have world area but no chart area. "World
    area" is measured against the object's largest triangle: against a scene's, a small object
    beside a large one had every triangle under the bar."""
    tiny = 1e-9 * max(float(np.max(world_area2, initial=0.0)), 1e-30)
    return (chart_area2 <= 1e-12) & (world_area2 > tiny)


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
    # box, not the square around it (with square grids the thin scene's sheet took a minute).
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
    # ufunc.at (a scatter with repeats) was the slowest step of a sheet build.
    stride = int(k.max(initial=0)) + 1
    key = np.sort(pix * stride + tri)
    texel = key // stride
    start = np.flatnonzero(np.r_[True, texel[1:] != texel[:-1]])
    t = texel[start]
    owner[t] = np.minimum(owner[t], key[start] - t * stride)
    hits[t] += np.diff(np.r_[start, key.size]).astype(hits.dtype)


def raster_owner(st: np.ndarray, res: int) -> tuple[np.ndarray, int, int]:
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
