"""Waves: how shading lanes are packed into SIMD waves of ``wave_size`` lanes, counted one way
for every pipeline.

Each pipeline groups its lanes the way its hardware counterpart launches them: forward packs
the 2x2 quads of one draw into waves in rasterization order (``draw_waves``); deferred and
checkerboard run a full-screen compute pass over 8x8 tiles, each split into waves of
consecutive rows; the visibility buffer packs the coarse pixels of one batch group in a
128x128 tile into waves (``loose_tiles``), or those of one (material, rate, 8x8 tile);
object-space shading launches whole 8x8 shadel chunks; DACS hands each warp a run of a level's
pixels. A group's lanes never share a wave with another group's, so the waves are the sum over
groups of ceil(lanes / wave_size), and the lane utilisation is the invocations over the lanes
those waves hold.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.types import Array

TILE = 8  # pixels per side of a compute tile
WAVE_SIZES = (32, 64)  # lanes per wave: the two widths GPUs run (32-lane warps, 64-lane waves)


def check_wave_size(wave_size: int) -> None:
    """Every pipeline config's check of its ``wave_size``."""
    if wave_size not in WAVE_SIZES:
        raise ValueError(f"wave_size must be 32 or 64, got {wave_size!r}")


def count_waves(group_lanes: Array, wave_size: int, invocations: Array) -> tuple[Array, Array]:
    """Waves for int32[G] lanes per group (any shape): sum of ceil(lanes / wave_size). Returns
    (waves int32, lane utilisation = invocations / (waves * wave_size), float32; 0 without
    waves)."""
    ws = int(wave_size)
    waves = jnp.sum((group_lanes + ws - 1) // ws, dtype=jnp.int32)
    util = jnp.asarray(invocations).astype(jnp.float32) / jnp.maximum(waves * ws, 1).astype(
        jnp.float32)
    return waves, util


def tile_rows(active: Array, wave_size: int) -> Array:
    """Active pixels per wave group of a full-screen pass over 8x8 tiles: each tile splits into
    64 / wave_size groups of consecutive rows. bool[H, W] -> int32[tiles, groups]."""
    h, w = active.shape
    th, tw = -(-h // TILE), -(-w // TILE)
    pad = jnp.zeros((th * TILE, tw * TILE), bool).at[:h, :w].set(active)
    groups = TILE * TILE // int(wave_size)
    per = pad.reshape(th, TILE, tw, TILE).transpose(0, 2, 1, 3).reshape(th * tw, groups, -1)
    return jnp.sum(per, axis=-1, dtype=jnp.int32)


def tile_waves(active: Array, wave_size: int, invocations: Array) -> tuple[Array, Array]:
    """Waves of a full-screen compute pass over 8x8 tiles (a wave runs if any of its pixels is
    active): ``count_waves`` of ``tile_rows``. Returns (waves int32, lane utilisation)."""
    return count_waves(tile_rows(active, wave_size), wave_size, invocations)


# A scatter-add of millions of entries into a few bins serialises on the bins' atomics (6 ms
# for the quads of foliage's handful of materials on an H200); spreading each bin over this many
# partial counters, summed afterwards, keeps the atomics apart.
SPREAD = 1024


def group_sizes(group: Array, live: Array, n_groups: int) -> Array:
    """int32[n_groups]: how many live entries of int32[N] ``group`` fall in each group."""
    n = group.shape[0]
    spread = max(1, min(SPREAD, (1 << 22) // max(int(n_groups), 1), n))
    lane = jnp.arange(n, dtype=jnp.int32) % spread
    partial = jnp.zeros((int(n_groups), spread), jnp.int32).at[
        jnp.where(live, group, n_groups), lane].add(1, mode="drop")
    return jnp.sum(partial, axis=1, dtype=jnp.int32)


def segment_lanes(starts: Array, live: Array) -> Array:
    """Items per segment of a sorted work list (``starts``: bool[N], True at each segment's
    first item; ``live``: the items that exist): int32[N], segment k's size at index k.

    Read off the segments' start positions (the live items before the next start, less those
    before this one), not by a scatter-add of every item into its segment: that serialises on
    the atomics of a long segment (a 128x128 tile of one material is 16k items; the scatter
    took 0.9-1.2 ms of the visibility buffer's frame on an H200)."""
    n = starts.shape[0]
    pos, _ = compact_indices(starts, n, fill_value=n)  # past the last segment: n, size 0
    live_before = jnp.concatenate([jnp.zeros((1,), jnp.int32),
                                   jnp.cumsum(live, dtype=jnp.int32)])  # [N + 1]
    end = jnp.concatenate([pos[1:], jnp.full((1,), n, jnp.int32)])
    return live_before[end] - live_before[pos]
