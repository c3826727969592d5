"""The DACS level pattern (Mallett and Yuksel, HPG 2018), static NumPy.

With an initial spacing s = 2^k, pixel (x, y) belongs to the level fixed by the lowest set bit
of x and y. (0, 0) mod s is level 0, always shaded. Then for d = s/2, s/4, ..., 1 come two
levels: the *diagonal* one, pixels whose x and y are both odd multiples of d, decided from the
four diagonal neighbours at distance d; and the *axis* one, pixels with exactly one coordinate
an odd multiple of d (the other a multiple of 2d), decided from the four axis neighbours at d.
For s = 4 these are the five levels of DACS (Mallett & Yuksel 2018): (0,0); (2,2); (0,2),(2,0);
the four (odd, odd); the remaining eight. Every parent lies on an earlier level, so the levels run in order.
"""

from __future__ import annotations

import numpy as np

SPACINGS = (4, 8)


def n_levels(spacing: int) -> int:
    return 1 + 2 * int(np.log2(spacing))


def level_step(level: int, spacing: int) -> tuple[int, bool]:
    """(d, diagonal) for level >= 1: parent distance and whether the parents are diagonal."""
    j = (level + 1) // 2  # d = spacing / 2^j
    return spacing >> j, level % 2 == 1


def parent_pairs(level: int, spacing: int) -> tuple[tuple[tuple[int, int], tuple[int, int]], ...]:
    """The four parents of ``level`` as two opposite pairs of (dy, dx) offsets."""
    d, diagonal = level_step(level, spacing)
    if diagonal:
        return (((-d, -d), (d, d)), ((-d, d), (d, -d)))
    return (((0, -d), (0, d)), ((-d, 0), (d, 0)))


def _lowbit(v: np.ndarray, cap: int) -> np.ndarray:
    """Largest power of two dividing v, capped at ``cap`` (0 -> cap)."""
    v = v.astype(np.int64)
    low = v & -v
    return np.where((v == 0) | (low > cap), cap, low)


def level_map(height: int, width: int, spacing: int = 4) -> np.ndarray:
    """int32[H, W]: the DACS level of each pixel."""
    if spacing not in SPACINGS:
        raise ValueError(f"spacing must be one of {SPACINGS}, got {spacing}")
    y = np.arange(height)[:, None]
    x = np.arange(width)[None, :]
    lx, ly = _lowbit(np.broadcast_to(x, (height, width)), spacing), _lowbit(
        np.broadcast_to(y, (height, width)), spacing)
    d = np.minimum(lx, ly)
    j = np.log2(spacing // d).astype(np.int32)  # 0 where d == spacing
    diagonal = lx == ly
    level = np.where(j == 0, 0, np.where(diagonal, 2 * j - 1, 2 * j))
    return level.astype(np.int32)


def level_pixels(height: int, width: int, spacing: int = 4) -> list[np.ndarray]:
    """Flat pixel indices (raster order) of each level."""
    lv = level_map(height, width, spacing).reshape(-1)
    return [np.flatnonzero(lv == k).astype(np.int32) for k in range(n_levels(spacing))]
