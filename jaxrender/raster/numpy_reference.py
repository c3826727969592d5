"""A small, readable NumPy rasterizer: the oracle the JAX rasterizer is tested against.

It follows the same rules one triangle at a time: clip in homogeneous space (same planes, same
float32 intersection arithmetic, so clipped vertices agree bit for bit), snap with the same
float32 operations, then exact edge functions in Python integers, the top-left rule, a depth
test in float64 with ties to the lower triangle index. It also records, per pixel, the gap
between the nearest and the second-nearest fragment depth, so tests can tell a genuine
mismatch from a depth tie that float32 and float64 may break differently.
"""

from __future__ import annotations

import numpy as np

from jaxrender.raster.clip import planes as clip_planes
from jaxrender.raster.setup import SUBPIXEL, guard_band


def _clip_polygon(tri: np.ndarray, guard: float) -> list[np.ndarray]:
    """Sutherland-Hodgman against the six planes, float32 as the JAX version computes it."""
    poly = [v.astype(np.float32) for v in tri]
    for plane in clip_planes(guard):
        out = []
        n = len(poly)
        for k in range(n):
            a, b = poly[k], poly[(k + 1) % n]
            da = np.float32(np.sum(a * plane, dtype=np.float32))
            db = np.float32(np.sum(b * plane, dtype=np.float32))
            if da >= 0:
                out.append(a)
            if (da >= 0) != (db >= 0):
                p_in, p_out, d_in, d_out = (a, b, da, db) if da >= 0 else (b, a, db, da)
                t = np.float32(d_in / np.float32(d_in - d_out))
                out.append((p_in + t * (p_out - p_in)).astype(np.float32))
        poly = out
        if not poly:
            return []
    return poly


def _snap(v: np.ndarray, width: int, height: int) -> tuple[int, int, float]:
    w = np.float32(v[3])
    x = np.round((np.float32(v[0]) / w + np.float32(1.0)) * np.float32(width * SUBPIXEL // 2))
    y = np.round((np.float32(1.0) - np.float32(v[1]) / w) * np.float32(height * SUBPIXEL // 2))
    z = float(v[2]) / float(v[3]) * 0.5 + 0.5
    return int(x), int(y), z


def rasterize_reference(clip, faces, width, height, *, cull_backfaces=False, offset=(0.5, 0.5)):
    """Returns dict(tri_id int32[H, W], depth float64[H, W], depth_gap float64[H, W],
    fragments int, coverage_count int32[H, W] (covered fragments per pixel))."""
    clip = np.asarray(clip, np.float32)
    faces = np.asarray(faces)
    guard = guard_band(width, height)
    ox, oy = (int(o * SUBPIXEL + 0.5) for o in offset)
    tri_id = np.full((height, width), -1, np.int32)
    depth = np.full((height, width), np.inf)
    second = np.full((height, width), np.inf)
    hits = np.zeros((height, width), np.int32)
    for t, face in enumerate(faces):
        tri = clip[face]
        if not np.all(np.isfinite(tri)):
            continue
        poly = _clip_polygon(tri, guard)
        for k in range(1, len(poly) - 1):
            _cover_triangle(
                [poly[0], poly[k], poly[k + 1]], t, width, height, (ox, oy), cull_backfaces,
                tri_id, depth, second, hits,
            )
    with np.errstate(invalid="ignore"):  # inf - inf where a pixel has fewer than two fragments
        gap = np.where(np.isfinite(second), second - depth, np.inf)
    depth = np.where(tri_id >= 0, np.clip(depth, 0.0, 1.0), 1.0)
    return dict(
        tri_id=tri_id, depth=depth, depth_gap=gap, fragments=int(hits.sum()), coverage_count=hits
    )


def _cover_triangle(tri, t, width, height, offset, cull, tri_id, depth, second, hits):
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = (_snap(v, width, height) for v in tri)
    area2 = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
    if area2 == 0 or (cull and area2 > 0):  # GL front faces have area2 < 0 with y down
        return
    sign = -1 if area2 < 0 else 1
    xs, ys, zs = (x0, x1, x2), (y0, y1, y2), (z0, z1, z2)
    ox, oy = offset
    px_lo = max(-((ox - min(xs)) // SUBPIXEL), 0)  # ceil((min - ox) / S)
    px_hi = min((max(xs) - ox) // SUBPIXEL, width - 1)
    py_lo = max(-((oy - min(ys)) // SUBPIXEL), 0)
    py_hi = min((max(ys) - oy) // SUBPIXEL, height - 1)
    if px_lo > px_hi or py_lo > py_hi:
        return
    py, px = np.mgrid[py_lo : py_hi + 1, px_lo : px_hi + 1]
    sx = px.astype(object) * SUBPIXEL + ox  # Python integers: exact at any size
    sy = py.astype(object) * SUBPIXEL + oy
    inside = np.ones(px.shape, bool)
    lam = []
    for i in range(3):  # edge i runs from vertex i+1 to vertex i+2, opposite vertex i
        a, b = (i + 1) % 3, (i + 2) % 3
        dx, dy = (xs[b] - xs[a]) * sign, (ys[b] - ys[a]) * sign
        e = dx * (sy - ys[a]) - dy * (sx - xs[a])
        top_left = dy < 0 or (dy == 0 and dx > 0)
        inside &= (e > 0) | ((e == 0) & top_left)
        lam.append(e.astype(np.float64) / abs(area2))
    z = lam[0] * zs[0] + lam[1] * zs[1] + lam[2] * zs[2]
    for yy, xx, zz in zip(py[inside], px[inside], z[inside]):
        hits[yy, xx] += 1
        if zz < depth[yy, xx] or (zz == depth[yy, xx] and t < tri_id[yy, xx]):
            second[yy, xx] = depth[yy, xx]
            depth[yy, xx], tri_id[yy, xx] = zz, t
        elif zz < second[yy, xx] and tri_id[yy, xx] != t:
            second[yy, xx] = zz
