"""Stream compaction: the indices of the True entries of a mask, in order, in a fixed-size list.

``jnp.nonzero(mask, size=n)`` does this with a scatter-add in which every False entry adds to
the same few addresses, and that contention dominated whole pipelines on a GPU (benchmarks/
RESULTS.md). Here each True entry writes its own slot (its rank, a prefix sum), so the scatter
has unique indices and no contention: O(n) work, two passes.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.types import Array


def compact_indices(mask: Array, size: int, fill_value: int = 0, start=0) -> tuple[Array, Array]:
    """(int32[size] indices of the True entries of bool[N] in increasing order, padded with
    ``fill_value``; their count int32, which may exceed ``size``: entries past it are not
    listed). ``start`` (may be traced) skips the first ``start`` True entries, so that a loop
    can list them ``size`` at a time."""
    mask = mask.reshape(-1)
    local = jnp.cumsum(mask, dtype=jnp.int32) - 1 - jnp.asarray(start, jnp.int32)
    dest = jnp.where(mask & (local >= 0), local, size)  # size: out of range, dropped
    idx = jnp.full((size,), fill_value, jnp.int32).at[dest].set(
        jnp.arange(mask.shape[0], dtype=jnp.int32), mode="drop", unique_indices=True)
    return idx, jnp.sum(mask, dtype=jnp.int32)
