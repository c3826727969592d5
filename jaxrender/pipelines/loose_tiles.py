"""Loose tiling, as Decima's visibility buffer classifies its pixels (GDC 2022).

The screen is cut into 128x128 tiles. Inside a tile the pixels to shade are sorted by batch
group (the shader they need: here the material), each group's pixels in Morton (Z) order of
their place in the tile, as a classification pass of 8x8 thread groups appends them (so a
full wave of 64 is an 8x8 block), and packed into complete waves of ``wave_size`` lanes;
only a group's last wave in a tile can have unfilled lanes. The classification writes a 16-bit
pixel command per lane (7 + 7 bits of position inside the tile, 2 bits of shading rate) and a
32-bit wave command per wave (where its pixel commands start, which tile and batch group).
The 8x8 material tiles it replaced (``tiling = "tiles"``) give every (material, tile) at
least one wave of its own.

Everything here reads the sorted work list that drives the shading: a (tile, group) segment
of it is one run of waves.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.quads import BIG, segment_starts
from jaxrender.pipelines.waves import count_waves, segment_lanes
from jaxrender.sorting import lex_sort
from jaxrender.types import Array

LOOSE_TILE = 128  # pixels per side of a loose tile
PIXEL_COMMAND_BYTES = 2  # 16 bits: x, y inside the tile (7 + 7) and the rate (2)
WAVE_COMMAND_BYTES = 4  # 32 bits: first pixel command, tile and batch group of one wave
TILINGS = ("loose", "tiles")


def loose_tile_index(x: Array, y: Array, width: int) -> Array:
    """int32: the 128x128 tile of pixel (x, y), row-major over the screen."""
    tiles_w = -(-width // LOOSE_TILE)
    return (y // LOOSE_TILE) * tiles_w + x // LOOSE_TILE


def morton(x: Array, y: Array) -> Array:
    """int32 Morton (Z-order) code of 7-bit x, y: their bits interleaved, x lowest."""
    code = jnp.zeros(jnp.shape(x), jnp.int32)
    for b in range(LOOSE_TILE.bit_length() - 1):
        code = code | (((x >> b) & 1) << (2 * b)) | (((y >> b) & 1) << (2 * b + 1))
    return code


def loose_order(live: Array, group: Array, x: Array, y: Array, width: int, height: int,
                n_groups: int) -> tuple[Array, Array, Array]:
    """The live entries (bool[N]; pixel ``x``, ``y``; batch group int32[N] in [0, n_groups))
    in loose-tile order: by tile, then batch group, then Morton order inside the tile.

    Returns (order int32[N]: entry indices, live ones first; segment starts bool[N]: True at
    the first entry of each (tile, group) run; live_sorted bool[N])."""
    n_tiles = -(-width // LOOSE_TILE) * -(-height // LOOSE_TILE)
    big = lambda a: jnp.where(live, a, BIG)  # noqa: E731
    idx = jnp.arange(live.shape[0], dtype=jnp.int32)
    (t_s, g_s, _), (order,) = lex_sort(
        (big(loose_tile_index(x, y, width)), big(group),
         big(morton(x % LOOSE_TILE, y % LOOSE_TILE))),
        (n_tiles - 1, n_groups - 1, LOOSE_TILE * LOOSE_TILE - 1), (idx,))
    live_s = t_s != BIG
    return order, segment_starts(t_s, g_s) & live_s, live_s


def command_counts(run_starts: Array, live_sorted: Array, wave_size: int, invocations: Array,
                   tiling: str) -> dict:
    """The wave and command counts of a sorted work list whose (tile, group) runs start at
    ``run_starts``: waves (each run in ceil(lanes / wave_size) waves), lane utilisation,
    unfilled lanes (lanes of launched waves that shade nothing) and the classification's
    command bytes. Under ``tiles`` a wave is an 8x8 tile's material mask: one 32-bit tile
    command per wave and no pixel commands."""
    lanes = segment_lanes(run_starts, live_sorted)
    waves, util = count_waves(lanes, wave_size, invocations)
    pixel_cmds = invocations if tiling == "loose" else jnp.int32(0)
    return {"waves": waves, "lane_utilization": util,
            "unfilled_lanes": waves * int(wave_size) - invocations,
            "pixel_command_bytes": pixel_cmds * PIXEL_COMMAND_BYTES,
            "wave_command_bytes": waves * WAVE_COMMAND_BYTES}
