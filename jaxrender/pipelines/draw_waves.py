"""Pixel-shader waves as hardware packs them: the 2x2 quads of one draw, in rasterization
order, fill waves of ``wave_size`` lanes (four lanes a quad, helper lanes included); a wave
never holds quads of two draws, so each draw's last wave may be partly filled.

A draw is a batch: a run of consecutive objects of one material and one triangle count drawn
as one instanced draw (``micro_batch.triangle_batches``; the visibility buffer's batches). The
waves are counted off the pass's quads, one unit of each (triangle, quad) marked: a draw's
quads fill its waves in order, so only each draw's quad count matters.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.waves import group_sizes
from jaxrender.types import Array


def draw_waves(tri_draw: Array, quad_start: Array, quad_tri: Array, wave_size: int,
               invocations: Array) -> dict:
    """Waves of the quads packed per draw (``tri_draw``: int32[T], each triangle's draw,
    numbered in draw order; ``quad_start``: bool[N], True at one unit of each quad;
    ``quad_tri``: int32[N], its triangle): {waves, lane_utilization (invocations over the
    waves' lanes), unfilled_lanes (lanes of launched waves that hold no quad)}. A draw of n
    quads fills ceil(n / (wave_size / 4)) waves, whatever order its quads come in."""
    n_draws = tri_draw.shape[0]  # at most one draw a triangle
    draw = tri_draw[jnp.clip(quad_tri, 0, n_draws - 1)]
    per_draw = group_sizes(draw, quad_start, n_draws)
    quads_per_wave = int(wave_size) // 4
    waves = jnp.sum((per_draw + quads_per_wave - 1) // quads_per_wave, dtype=jnp.int32)
    lanes = waves * int(wave_size)
    util = jnp.asarray(invocations).astype(jnp.float32) / jnp.maximum(lanes, 1).astype(
        jnp.float32)
    return {"waves": waves, "lane_utilization": util,
            "unfilled_lanes": lanes - 4 * jnp.sum(per_draw, dtype=jnp.int32)}
