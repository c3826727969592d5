"""Object-space shading: the store's budget fed back across frames (``bias_feedback``), as in
Baker and Jarzynski (EGSR 2022): frame t+1's global MIP bias comes from frame t's allocation.

Without it (os_alloc) a frame raises its bias and marks again until its chunks fit (GDC 2016:
"all objects are progressively scaled until it fits"). With it a frame marks once, at the bias
the previous frame chose, allocates what the store holds and leaves the rest unshaded, then sets
the next frame's bias from what it asked for (``next_bias``), with hysteresis:

- requested > capacity (some chunk left unshaded): raise by ``bias_step`` (fast);
- requested < ``bias_low`` x capacity: relax by ``bias_relax`` (slowly, down to ``mip_bias``);
- otherwise hold. A band wider than the growth one relaxation step causes (a request grows
  about 4^bias_relax per step: 1.09x at the default 1/16, inside 1 / 0.8) keeps a view whose
  demand varies smoothly from oscillating between raising and relaxing.

The EG 2022 paper's own threshold values were not found in the sources available here; these
are the defaults (``ObjectSpaceConfig``), stated wherever they are reported.

Unshaded chunks leave no holes: when a frame is over budget, the coarsest level (one chunk) of
every visible object is allocated first, then the marked chunks coarsest level first (a coarse
chunk serves the most pixels per shadel), and a pixel with a tap in an unshaded chunk reads its
object's coarsest level instead (the coarsest MIP always resident, as virtual texturing does).
Counted: chunks requested, allocated and left unshaded, and the pixels that fell back. Only a
store smaller than those coarsest chunks overflows (loudly). A frame within budget allocates
exactly as os_alloc does at the same bias.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.pipelines.os_alloc import Allocation
from jaxrender.pipelines.os_marking import Footprint, Taps, mark_chunks, raw_lod, taps
from jaxrender.pipelines.os_sheet import ShadeSheet
from jaxrender.types import Array

# A bias past every level of every object (raw LODs are bounded below by log2(1e-20) ~ -66):
# the taps it gives sit at each object's coarsest level.
COARSEST_BIAS = 256.0


class Budget(NamedTuple):
    """A feedback frame's allocation statistics: ``bias`` (used), ``requested`` (chunks marked
    at it), ``unshaded`` (of those, not allocated), ``fallback_pixels`` (pixels that read their
    object's coarsest level for want of a chunk) and ``next_bias`` (the next frame's)."""

    bias: Array
    requested: Array
    unshaded: Array
    fallback_pixels: Array
    next_bias: Array


def check_config(cfg) -> None:
    """The feedback settings: valid, and refused (named) where they cannot act."""
    if not 0.0 < cfg.bias_low <= 1.0:
        raise ValueError(f"object_space: invalid bias_low = {cfg.bias_low!r} (a fraction of "
                         f"the store in (0, 1])")
    if not cfg.bias_relax > 0.0:
        raise ValueError(f"object_space: invalid bias_relax = {cfg.bias_relax!r} (> 0)")
    if not cfg.bias_feedback:
        cls = type(cfg)
        for k in ("bias_low", "bias_relax"):
            if getattr(cfg, k) != getattr(cls, k):
                raise ValueError(f"object_space: {k} = {getattr(cfg, k)!r} has no effect "
                                 f"without bias_feedback = true")


def priority_rank(marked: Array, coarsest: Array, sheet: ShadeSheet) -> Array:
    """int32[NC]: each marked chunk's place in the store when not all fit: the ``coarsest``
    chunks first, then the others level by level from the coarsest, in chunk order within a
    class (unmarked chunks: unspecified)."""
    top = sheet.max_levels - 1
    cls = jnp.where(coarsest, 0, 1 + top - sheet.chunk_level)
    rank = jnp.zeros(marked.shape, jnp.int32)
    base = jnp.int32(0)
    for c in range(sheet.max_levels + 1):
        m = marked & (cls == c)
        rank = jnp.where(m, base + jnp.cumsum(m, dtype=jnp.int32) - 1, rank)
        base = base + jnp.sum(m, dtype=jnp.int32)
    return rank


def _choose(miss: Array, fallback: Taps, wanted: Taps) -> Taps:
    pick = lambda f, w: jnp.where(miss[:, None], f, w)  # noqa: E731
    return Taps(pick(fallback.chunk, wanted.chunk), pick(fallback.lane, wanted.lane),
                pick(fallback.weight, wanted.weight), jnp.where(miss, fallback.lod, wanted.lod))


def allocate_budget(fp: Footprint, sheet: ShadeSheet, capacity: int, bias: Array, mode: str,
                    aniso_taps: int) -> tuple[Allocation, Array, Array, Array]:
    """One marking at ``bias``, allocated into ``capacity`` chunks (see the module doc).
    Returns (the Allocation, whose taps are those the final pass reads; chunks requested;
    chunks left unshaded; pixels that fell back to their object's coarsest level)."""
    nc = sheet.n_chunks
    bias = jnp.asarray(bias, jnp.float32)
    wanted = taps(fp, sheet, bias, mode, aniso_taps)
    want = mark_chunks(wanted, nc)
    requested = jnp.sum(want, dtype=jnp.int32)
    over = requested > capacity
    fallback = taps(fp, sheet, jnp.float32(COARSEST_BIAS), mode, aniso_taps)
    coarsest = mark_chunks(fallback, nc) & over
    marked = want | coarsest
    n = jnp.sum(marked, dtype=jnp.int32)
    rank = jnp.where(over, priority_rank(marked, coarsest, sheet),
                     jnp.cumsum(marked, dtype=jnp.int32) - 1)
    page = jnp.where(marked & (rank < capacity), rank, -1)
    slot_chunk = jnp.full((capacity,), -1, jnp.int32).at[jnp.where(page >= 0, page, capacity)].set(
        jnp.arange(nc, dtype=jnp.int32), mode="drop")
    read = lambda t: t.weight > 0.0  # noqa: E731
    miss = jnp.any(read(wanted) & (page[wanted.chunk] < 0), axis=1)
    lost = jnp.any(read(fallback) & (page[fallback.chunk] < 0), axis=1)
    overflow = jnp.any(miss & lost).astype(jnp.int32)  # the store holds not even those
    al = Allocation(_choose(miss, fallback, wanted), marked, page, slot_chunk,
                    jnp.minimum(n, capacity), bias, jnp.int32(0), overflow)
    unshaded = jnp.sum(want & (page < 0), dtype=jnp.int32)
    return al, requested, unshaded, jnp.sum(miss, dtype=jnp.int32)


def max_useful_bias(fp: Footprint, sheet: ShadeSheet, aniso_taps: int) -> Array:
    """The bias past which every covered pixel sits at its object's coarsest level (raising
    further changes nothing), as os_alloc bounds its retries."""
    lod, _, top = raw_lod(fp, sheet, aniso_taps)
    return jnp.max(jnp.where(fp.covered, top - lod, 0.0), initial=0.0) + 1.0


def next_bias(bias: Array, requested: Array, capacity: int, cfg, ceiling: Array) -> Array:
    """The next frame's bias from this frame's request (thresholds in the module doc), kept in
    [mip_bias, max(ceiling, mip_bias)]."""
    cap = jnp.float32(capacity)
    req = requested.astype(jnp.float32)
    b = jnp.where(req > cap, bias + jnp.float32(cfg.bias_step),
                  jnp.where(req < jnp.float32(cfg.bias_low) * cap,
                            bias - jnp.float32(cfg.bias_relax), bias))
    floor = jnp.float32(cfg.mip_bias)
    return jnp.clip(b, floor, jnp.maximum(ceiling, floor)).astype(jnp.float32)


def feedback_allocate(fp: Footprint, sheet: ShadeSheet, cfg, bias: Array
                      ) -> tuple[Allocation, Budget]:
    """The Allocation of a feedback frame starting from the carried ``bias``, and its Budget."""
    cap = cfg.store_chunks
    with jax.named_scope("bias_feedback"):
        al, requested, unshaded, fell = allocate_budget(fp, sheet, cap, bias, cfg.filter,
                                                        cfg.aniso_taps)
        ceiling = max_useful_bias(fp, sheet, cfg.aniso_taps)
        nb = next_bias(al.bias, requested, cap, cfg, ceiling)
    return al, Budget(al.bias, requested, unshaded, fell, nb)


def budget_counts(b: Budget) -> dict:
    return {"chunks_requested": b.requested, "chunks_unshaded": b.unshaded,
            "fallback_pixels": b.fallback_pixels, "mip_bias_next": b.next_bias}


__all__ = ["Budget", "COARSEST_BIAS", "allocate_budget", "budget_counts", "check_config",
           "feedback_allocate", "max_useful_bias", "next_bias", "priority_rank"]
