"""Sub-pixel sample patterns: static tuples of (x, y) offsets in [0, 1) from a pixel's corner.

(0.5, 0.5) is the pixel centre (GL/D3D). The rasterizer snaps every offset to the 8-bit
sub-pixel grid, as hardware does; patterns here are chosen to lie on that grid (multiples of
1/16 for MSAA, as the D3D standard patterns are given).
"""

from __future__ import annotations

CENTER: tuple[tuple[float, float], ...] = ((0.5, 0.5),)

# D3D11 standard sample positions, in 1/16 pixel units relative to the pixel centre
# (D3D11_STANDARD_MULTISAMPLE_PATTERN; y grows downwards, as our image rows do).
_D3D_STANDARD = {
    1: ((0, 0),),
    2: ((4, 4), (-4, -4)),
    4: ((-2, -6), (6, -2), (-6, 2), (2, 6)),
    8: ((1, -3), (-1, 3), (5, 1), (-3, -5), (-5, 5), (-7, -1), (3, 7), (7, -7)),
}


def msaa(count: int) -> tuple[tuple[float, float], ...]:
    """The standard MSAA pattern with ``count`` in (1, 2, 4, 8) samples."""
    if count not in _D3D_STANDARD:
        raise ValueError(f"msaa: sample count must be one of 1, 2, 4, 8, got {count}")
    return tuple((0.5 + dx / 16.0, 0.5 + dy / 16.0) for dx, dy in _D3D_STANDARD[count])


def stratified(k: int) -> tuple[tuple[float, float], ...]:
    """k x k cell centres: the reference's stratified supersampling pattern (row-major)."""
    if k < 1:
        raise ValueError(f"stratified: k must be >= 1, got {k}")
    return tuple(((i + 0.5) / k, (j + 0.5) / k) for j in range(k) for i in range(k))


def validate(offsets) -> tuple[tuple[float, float], ...]:
    offsets = tuple((float(x), float(y)) for x, y in offsets)
    if not offsets:
        raise ValueError("sample_offsets: need at least one offset")
    for x, y in offsets:
        if not (0.0 <= x < 1.0 and 0.0 <= y < 1.0):
            raise ValueError(f"sample_offsets: ({x}, {y}) must lie in [0, 1) x [0, 1)")
    return offsets


def to_fixed(offsets, subpixel_bits: int) -> tuple[tuple[int, int], ...]:
    """Offsets on the fixed-point sub-pixel grid (round half up, as positions are snapped)."""
    scale = 1 << subpixel_bits
    return tuple((int(x * scale + 0.5), int(y * scale + 0.5)) for x, y in offsets)
