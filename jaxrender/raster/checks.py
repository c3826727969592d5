"""Input checks of the raster entry points: sizes, mesh shapes, dtypes and index ranges.

Only what shapes and dtypes can tell is checked under a trace; index ranges are checked when
the faces are concrete.
"""

from __future__ import annotations

import weakref
from functools import lru_cache

import jax
import numpy as np


def check_size(width, height) -> tuple[int, int]:
    for name, v in (("width", width), ("height", height)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v <= 0:
            raise ValueError(f"rasterize: {name} must be a positive integer, got {v!r}")
    if width * height >= 2**31:
        raise ValueError(f"rasterize: {width}x{height} has too many pixels (limit 2^31)")
    return int(width), int(height)


def check_mesh(verts, faces, what: str, dim: int) -> None:
    """Checks that need only shapes and dtypes; values are checked when they are concrete."""
    n_verts = np.shape(verts)[0] if np.ndim(verts) else 0
    _check_shapes(np.shape(verts), _dtype(verts), np.shape(faces), _dtype(faces), what, dim)
    if not isinstance(faces, jax.core.Tracer):
        lo, hi = _index_range(faces)
        if lo < 0 or hi >= n_verts:
            bad = lo if lo < 0 else hi
            raise ValueError(f"rasterize: face index {bad} out of range for {n_verts} vertices")


def _dtype(x) -> np.dtype:
    return np.dtype(x.dtype if hasattr(x, "dtype") else np.asarray(x).dtype)


@lru_cache(maxsize=256)
def _check_shapes(vshape, vdtype, fshape, fdtype, what: str, dim: int) -> None:
    if len(vshape) != 2 or vshape[1] != dim:
        raise ValueError(f"rasterize: {what} must have shape (V, {dim}), got {vshape}")
    if len(fshape) != 2 or fshape[1] != 3:
        raise ValueError(f"rasterize: faces must have shape (T, 3), got {fshape}")
    if vshape[0] == 0 or fshape[0] == 0:
        raise ValueError(f"rasterize: empty mesh ({vshape[0]} vertices, {fshape[0]} faces)")
    if not np.issubdtype(fdtype, np.integer):
        raise TypeError(f"rasterize: faces must be integers, got dtype {fdtype}")
    if not np.issubdtype(vdtype, np.floating):
        raise TypeError(f"rasterize: {what} must be floating point")
    if fshape[0] >= 2**31 - 1:
        raise ValueError("rasterize: too many triangles for 32-bit ids")


_INDEX_RANGES: dict[int, tuple[weakref.ref, int, int]] = {}


def _index_range(faces) -> tuple[int, int]:
    """(min, max) of a concrete index array, remembered for device arrays (immutable) while
    they live: a frame loop passing the same faces would otherwise copy them to the host every
    frame to check them."""
    hit = _INDEX_RANGES.get(id(faces))
    if hit is not None and hit[0]() is faces:
        return hit[1], hit[2]
    f = np.asarray(faces)
    lo, hi = int(f.min()), int(f.max())
    if isinstance(faces, jax.Array):
        key = id(faces)
        _INDEX_RANGES[key] = (weakref.ref(faces, lambda _: _INDEX_RANGES.pop(key, None)), lo, hi)
    return lo, hi
