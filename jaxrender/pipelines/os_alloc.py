"""Object-space shading, step 4: marked chunks allocated into a fixed physical store.

The store holds ``capacity`` chunks of 64 shadels. When the marked chunks do not fit, a global
MIP bias (the same for every object, fractional) is raised in steps of ``bias_step`` and the
marking redone, until they fit, as Oxide does; the bias is reported. If even the bias that puts
every pixel at its object's coarsest level does not fit, ``overflow`` is set (the frame is then
poisoned and an eager call raises): nothing is dropped silently.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.pipelines.os_marking import Footprint, Taps, mark_chunks, raw_lod, taps
from jaxrender.pipelines.os_sheet import ShadeSheet
from jaxrender.types import Array


class Allocation(NamedTuple):
    """taps: the final taps; marked bool[NC]; page int32[NC] (slot or -1); slot_chunk
    int32[cap] (virtual chunk of each slot, -1 free); n_alloc, bias, bias_steps, overflow."""

    taps: Taps
    marked: Array
    page: Array
    slot_chunk: Array
    n_alloc: Array
    bias: Array
    bias_steps: Array
    overflow: Array


def allocate(fp: Footprint, sheet: ShadeSheet, capacity: int, bias0: float, bias_step: float,
             mode: str, aniso_taps: int) -> Allocation:
    nc = sheet.n_chunks

    def mark(bias):
        t = taps(fp, sheet, bias, mode, aniso_taps)
        m = mark_chunks(t, nc)
        return t, m, jnp.sum(m, dtype=jnp.int32)

    # Past this bias every covered pixel sits at its object's coarsest level: raising it
    # further cannot reduce the work.
    lod, _, top = raw_lod(fp, sheet, aniso_taps)
    max_bias = jnp.max(jnp.where(fp.covered, top - lod, 0.0), initial=0.0) + 1.0

    def cond(c):
        bias, _, _, n, _ = c
        return (n > capacity) & (bias < max_bias)

    def body(c):
        bias, _, _, _, k = c
        bias = bias + jnp.float32(bias_step)
        return (bias, *mark(bias), k + 1)

    # The taps and marking of the last bias tried are the ones allocated: carried out of the
    # loop, not redone (the taps are a few values a pixel and tap, the marking a scatter over
    # them all).
    b0 = jnp.float32(bias0)
    bias, t, marked, n, steps = jax.lax.while_loop(cond, body,
                                                   (b0, *mark(b0), jnp.int32(0)))
    rank = jnp.cumsum(marked, dtype=jnp.int32) - 1
    page = jnp.where(marked & (rank < capacity), rank, -1)
    ids, _ = compact_indices(marked, capacity, fill_value=-1)
    n_alloc = jnp.minimum(n, capacity)
    return Allocation(t, marked, page, ids, n_alloc, bias, steps,
                      (n > capacity).astype(jnp.int32))
