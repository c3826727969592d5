"""Pixel-shader waves as hardware packs them: the 2x2 quads of one draw, in rasterization
order, fill waves of ``wave_size`` lanes (four lanes a quad, helper lanes included); a wave
never holds quads of two draws, so each draw's last wave may be partly filled.

A draw is a batch: a run of consecutive objects of one material and one triangle count drawn
as one instanced draw (``micro_batch.triangle_batches``; the visibility buffer's batches). The
waves are read off the quad list that drives the pass (``quads.quad_list``: sorted by
triangle, then quad; objects own contiguous triangles, so that is draw order and, inside a
draw, rasterization order).
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.quads import BIG, first_of_segment_index, segment_starts
from jaxrender.types import Array


def draw_waves(tri_draw: Array, ql: dict, wave_size: int, invocations: Array) -> dict:
    """Waves of the quads of ``ql`` packed per draw (``tri_draw``: int32[T], each triangle's
    draw): {waves, lane_utilization (invocations
    over the waves' lanes), unfilled_lanes (lanes of launched waves that hold no quad)}."""
    start = ql["start"]  # first unit of each quad, in draw and rasterization order
    draw = jnp.where(start, tri_draw[jnp.where(start, ql["tri"], 0)], BIG)
    # Only the quads matter: a quad's draw, carried forward so a draw change is seen at the
    # next quad whatever the non-quad entries between hold.
    quad_rank = jnp.cumsum(start, dtype=jnp.int32) - 1
    n = start.shape[0]
    draw_of_quad = jnp.full((n,), BIG, jnp.int32).at[jnp.where(start, quad_rank, n)].set(
        draw, mode="drop")
    live = jnp.arange(n, dtype=jnp.int32) < ql["n_quads"]
    new_draw = segment_starts(draw_of_quad) & live
    # The rank of each quad inside its draw: quads since the draw's first one.
    rank_in_draw = jnp.arange(n, dtype=jnp.int32) - first_of_segment_index(new_draw)
    quads_per_wave = int(wave_size) // 4
    new_wave = live & (rank_in_draw % quads_per_wave == 0)
    waves = jnp.sum(new_wave, dtype=jnp.int32)
    lanes = waves * int(wave_size)
    util = jnp.asarray(invocations).astype(jnp.float32) / jnp.maximum(lanes, 1).astype(
        jnp.float32)
    return {"waves": waves, "lane_utilization": util,
            "unfilled_lanes": lanes - 4 * ql["n_quads"]}
