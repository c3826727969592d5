"""Procedural meshes for raster tests and benchmarks (no downloads): a heightfield terrain grid
with an exact triangle count, and a closed UV sphere. NumPy only."""

from __future__ import annotations

import numpy as np


def grid_mesh(nx: int, ny: int, *, extent=(-1.0, 1.0, -1.0, 1.0), jitter=0.0, seed=0):
    """A (nx x ny)-cell grid of 2*nx*ny triangles sharing edges, as (vertices[V,2], faces[T,3]).

    ``jitter`` moves interior vertices by up to that fraction of a cell (shared edges stay shared).
    """
    x0, x1, y0, y1 = extent
    xs, ys = np.meshgrid(np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1))
    verts = np.stack([xs, ys], -1).reshape(-1, 2)
    if jitter:
        rng = np.random.default_rng(seed)
        cell = np.array([(x1 - x0) / nx, (y1 - y0) / ny])
        interior = np.zeros((ny + 1, nx + 1), bool)
        interior[1:-1, 1:-1] = True
        d = rng.uniform(-jitter, jitter, verts.shape) * cell
        verts = verts + d * interior.reshape(-1, 1)
    i = np.arange(ny)[:, None] * (nx + 1) + np.arange(nx)[None, :]
    a, b, c, d = i, i + 1, i + nx + 1, i + nx + 2
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)], 0).reshape(-1, 3)
    return verts, faces.astype(np.int32)


def terrain(n_tris: int, *, seed=0):
    """A heightfield of about ``n_tris`` triangles in world space (x, z in [-50, 50])."""
    n = max(1, int(round(np.sqrt(n_tris / 2))))
    v2, faces = grid_mesh(n, n, extent=(-50, 50, -50, 50), jitter=0.3, seed=seed)
    x, z = v2[:, 0], v2[:, 1]
    rng = np.random.default_rng(seed)
    k = rng.uniform(0.05, 0.3, (4, 2))
    h = sum(np.sin(k[i, 0] * x + i) * np.cos(k[i, 1] * z - i) for i in range(4)) * 2.0
    return np.stack([x, h, z], -1).astype(np.float32), faces


def uv_sphere(n_lat: int, n_lon: int, radius=1.0, center=(0.0, 0.0, 0.0)):
    """A closed, consistently wound UV sphere (poles shared, seam shared)."""
    lat = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    ring = np.stack(
        [np.sin(lat)[:, None] * np.cos(lon), np.cos(lat)[:, None] + 0 * lon,
         np.sin(lat)[:, None] * np.sin(lon)], -1
    ).reshape(-1, 3)
    verts = np.concatenate([[[0, 1, 0]], ring, [[0, -1, 0]]]) * radius + np.asarray(center)
    faces = []
    top, bottom = 0, len(verts) - 1
    idx = lambda r, c: 1 + r * n_lon + (c % n_lon)  # noqa: E731
    for c in range(n_lon):
        faces.append([top, idx(0, c + 1), idx(0, c)])
        faces.append([bottom, idx(n_lat - 2, c), idx(n_lat - 2, c + 1)])
        for r in range(n_lat - 2):
            faces.append([idx(r, c), idx(r, c + 1), idx(r + 1, c + 1)])
            faces.append([idx(r, c), idx(r + 1, c + 1), idx(r + 1, c)])
    return verts.astype(np.float32), np.asarray(faces, np.int32)
