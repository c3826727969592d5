"""A simulation of DACS's warp scheme, driven by the decisions the image used.

Per level, the level's pixels (raster order) are handed to warps of ``W`` lanes, each warp
taking ``batches`` consecutive groups of ``W`` pixels. A warp alternates two modes:

- SEARCH: one SIMD step; every lane tests one pixel (parents similar?) and either writes the
  interpolated colour or pushes the pixel onto the warp's queue (capacity 2W: it holds fewer
  than W before a search step and a step adds at most W).
- SHADE: whenever the queue holds at least W pixels, one SIMD step shades W of them with every
  lane busy. At the end of the level (a barrier: the next level reads these colours) a last,
  partial SHADE step drains what is left.

Reported (all read off the decision masks): search, shade and total SIMD steps, the lane
utilisation of the whole scheme and of its SHADE steps, and for comparison the naive scheme
without a queue, where a search step with any pixel to shade is followed by a divergent shade
step using only those lanes.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.waves import count_waves
from jaxrender.types import Array

WARP_WIDTHS = (32, 64)


def simulate_level(need: Array, width: int, batches: int) -> dict:
    """``need`` bool[N]: the level's pixels (in order) that are shaded. Returns int32 counts.

    The queue needs no step-by-step replay: it holds fewer than ``width`` pixels before each
    search step and gains at most ``width``, so after a warp's k-th step it holds its first k
    steps' pushes modulo ``width`` and has run one full SHADE step per ``width`` of them; its
    SHADE steps, the final partial one included, number ceil(pushes / width). Closed form, so
    the program holds no loop of tiny steps for counts alone."""
    n = need.shape[0]
    per_warp = width * batches
    warps = max(-(-n // per_warp), 1)
    pad = warps * per_warp - n
    groups = jnp.concatenate([need, jnp.zeros((pad,), bool)]).reshape(warps * batches, width)
    pushes = jnp.sum(groups.reshape(warps, per_warp), axis=1, dtype=jnp.int32)
    i32 = lambda a: jnp.sum(a, dtype=jnp.int32)
    # The level's search steps, over all its warps: its groups of ``width`` pixels.
    search = jnp.int32(-(-n // width))
    shade = i32((pushes + width - 1) // width)
    # The warps launched: the level's pixels in runs of per_warp, one warp per run.
    launched, _ = count_waves(jnp.asarray([n], jnp.int32), per_warp, jnp.int32(0))
    return {"search_steps": search, "shade_steps": shade,
            "naive_shade_steps": i32(jnp.any(groups, axis=1)),
            "searched": jnp.int32(n), "shaded": i32(need), "warps": launched}


def simulate(needs: list[Array], width: int = 32, batches: int = 4) -> dict:
    """Counts of the warp scheme over all levels; ``needs[k]`` is level k's shaded mask over
    its pixels in order. Keys are prefixed ``warp_`` / ``naive_`` for a Frame's counts."""
    if width not in WARP_WIDTHS:
        raise ValueError(f"warp width must be one of {WARP_WIDTHS}, got {width}")
    per = [simulate_level(nd, width, batches) for nd in needs if nd.shape[0] > 0]
    tot = {k: sum(p[k] for p in per) for k in per[0]}
    w = jnp.float32(width)
    steps = tot["search_steps"] + tot["shade_steps"]
    useful = (tot["searched"] + tot["shaded"]).astype(jnp.float32)
    naive_steps = tot["search_steps"] + tot["naive_shade_steps"]
    f = lambda a: jnp.maximum(a, 1).astype(jnp.float32) * w
    return {
        "warp_simd_steps": steps,
        "warp_search_steps": tot["search_steps"],
        "warp_shade_steps": tot["shade_steps"],
        "warp_lane_utilization": useful / f(steps),
        "warp_shade_utilization": tot["shaded"].astype(jnp.float32) / f(tot["shade_steps"]),
        "warps": tot["warps"],
        "naive_simd_steps": naive_steps,
        "naive_lane_utilization": useful / f(naive_steps),
        "naive_shade_utilization": tot["shaded"].astype(jnp.float32) / f(tot["naive_shade_steps"]),
    }
