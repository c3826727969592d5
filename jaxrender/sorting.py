"""Lexicographic sorts of small non-negative integer keys through one packed integer key.

``lax.sort`` with several key operands compiles, on a GPU, to a comparison sort over every
operand (about 40 passes over the fragments). When
the keys' static ranges fit in 63 bits together they are packed into one int64 (or int32) and
sorted with a permutation index: a single-key sort, which XLA hands to a radix sort, and the
other operands follow through one gather.
"""

from __future__ import annotations

from collections.abc import Sequence

import jax
import jax.numpy as jnp

from jaxrender.types import Array

EMPTY = 2**31 - 1  # a key outside its range sorts after every value in it and comes back as this


def lex_sort(keys: Sequence[Array], limits: Sequence[int], payloads: Sequence[Array] = ()
             ) -> tuple[list[Array], list[Array]]:
    """Sort int32[N] ``keys`` lexicographically (the first most significant), stably, carrying
    ``payloads`` (arrays with leading axis N). Key i holds values in [0, limits[i]] (static); a
    value outside that range (e.g. EMPTY for an unused entry) sorts after all of them and is
    returned as EMPTY. Returns (sorted keys, sorted payloads)."""
    keys = [jnp.asarray(k, jnp.int32) for k in keys]
    bits = [(int(lim) + 1).bit_length() for lim in limits]
    idx = jnp.arange(keys[0].shape[0], dtype=jnp.int32)
    if sum(bits) > 63:  # too wide to pack: a comparison sort on every key
        codes = [jnp.where((k < 0) | (k > lim), EMPTY, k) for k, lim in zip(keys, limits)]
        *out_keys, perm = jax.lax.sort((*codes, idx), num_keys=len(keys), is_stable=True)
        return out_keys, [p[perm] for p in payloads]
    # The entry's index as the last key when it fits: keys become unique, so the sort needs no
    # stability and sorts one operand (a stable or two-operand sort may not be given to the
    # radix sort: XLA's StableSortExpander rewrites its comparator).
    idx_bits = max(int(keys[0].shape[0]) - 1, 1).bit_length()
    with_index = sum(bits) + idx_bits <= 63
    total = sum(bits) + (idx_bits if with_index else 0)
    with jax.enable_x64(total > 31):
        wide = jnp.int64 if total > 31 else jnp.int32
        packed = jnp.zeros(keys[0].shape, wide)
        for k, lim, b in zip(keys, limits, bits):
            code = jnp.where((k < 0) | (k > lim), lim + 1, k).astype(wide)
            packed = (packed << b) | code
        if with_index:
            packed = jax.lax.sort((packed << idx_bits) | idx.astype(wide), is_stable=False)
            perm = (packed & ((1 << idx_bits) - 1)).astype(jnp.int32)
            packed = packed >> idx_bits
        else:
            packed, perm = jax.lax.sort((packed, idx), num_keys=1, is_stable=True)
        out_keys, shift = [], sum(bits)
        for lim, b in zip(limits, bits):
            shift -= b
            v = ((packed >> shift) & ((1 << b) - 1)).astype(jnp.int32)
            out_keys.append(jnp.where(v > lim, EMPTY, v))
    return out_keys, [p[perm] for p in payloads]


# The prefix lengths ``lex_sort_prefix`` sorts, as fractions of the list: a fragment list's
# capacity is a few times what a frame fills, and a radix sort costs what it sorts.
PREFIX_FRACTIONS = (1 / 8, 3 / 16, 1 / 4, 3 / 8, 1 / 2, 3 / 4)


def prefix_sizes(n: int) -> list[int]:
    """The static prefix lengths ``lex_sort_prefix`` chooses from for a list of ``n``."""
    return sorted({max(1, -(-n * int(f * 16) // 16)) for f in PREFIX_FRACTIONS} | {n})


def lex_sort_prefix(keys: Sequence[Array], limits: Sequence[int], payloads: Sequence[Array],
                    count: Array) -> tuple[list[Array], list[Array]]:
    """``lex_sort`` of a list whose entries at and past ``count`` (int32, traced) are empty:
    every key of those entries is out of its range. Sorts only the shortest prefix of
    ``prefix_sizes`` that holds ``count`` entries (one ``lax.switch``); the empty tail comes
    back as ``lex_sort`` returns it, keys EMPTY, in index order. Same result as ``lex_sort``."""
    keys = [jnp.asarray(k, jnp.int32) for k in keys]
    n = keys[0].shape[0]
    sizes = prefix_sizes(n)

    def sort_first(m: int):
        def branch(operands):
            ks, ps = operands
            head_k, head_p = lex_sort([k[:m] for k in ks], limits, [p[:m] for p in ps])
            tail = jnp.full((n - m,), EMPTY, jnp.int32)
            return ([jnp.concatenate([h, tail]) for h in head_k],
                    [jnp.concatenate([h, p[m:]]) for h, p in zip(head_p, ps)])
        return branch

    which = sum((jnp.asarray(count) > m).astype(jnp.int32) for m in sizes[:-1])
    return jax.lax.switch(which, [sort_first(m) for m in sizes], (keys, list(payloads)))
