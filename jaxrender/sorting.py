"""Lexicographic sorts of small non-negative integer keys through packed integer keys.

``lax.sort`` with several key operands, or with one key and a stable order, has compiled on a
GPU to a comparison sort (about 40 passes over an 8M-entry list; XLA's StableSortExpander
rewrites a stable sort's comparator; ``pair_sort``'s stable sort is an exception). The keys
are instead packed, with the entry's index as the least significant field, into one int64
(or int32) per entry: unique keys of a single operand, which need no stability and which XLA
hands to a radix sort; the other operands follow through one gather. Keys that fit 64 bits
but not beside the index are one stable sort of the packed key with the index as its second
operand (``pair_sort``, on CUDA); wider keys are sorted one group at a time, least
significant first, each pass such a single-operand sort.
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
    codes, bits = key_codes(keys, limits)
    n = codes[0].shape[0]
    # Keys too wide for one packed key beside the index are sorted a group at a time, least
    # significant first (an LSD radix sort over the groups), unless they fit one uint64
    # without the index (``pair_sort``).
    idx_bits = max(int(n) - 1, 1).bit_length()
    groups = key_groups(bits, 63 - idx_bits)
    # Keys of at most 32 bits whose index would widen the packed key to an int64: a uint32
    # key beside an int32 index is half the radix passes of one int64 key.
    narrow = sum(bits) <= 32 < sum(bits) + idx_bits
    if narrow or (len(groups) > 1 and sum(bits) <= 64):
        # One pairs sort on a GPU (``pair_sort``); XLA:CPU's stable two-operand sort is a
        # comparison sort, slower there than the packed sorts (RESULTS.md).
        return jax.lax.platform_dependent(
            codes, payloads, cuda=lambda c, p: pair_sort(c, bits, limits, p),
            default=lambda c, p: packed_sorts(c, bits, limits, p, groups, idx_bits))
    return packed_sorts(codes, bits, limits, payloads, groups, idx_bits)


def key_codes(keys: Sequence[Array], limits: Sequence[int]) -> tuple[list[Array], list[int]]:
    """(each key as int32 with a value outside [0, limit] replaced by limit + 1, each key's
    bit width: enough for limit + 1)."""
    keys = [jnp.asarray(k, jnp.int32) for k in keys]
    bits = [(int(lim) + 1).bit_length() for lim in limits]
    return [jnp.where((k < 0) | (k > lim), lim + 1, k) for k, lim in zip(keys, limits)], bits


def packed_sorts(codes, bits, limits, payloads, groups, idx_bits):
    """``lex_sort`` as one single-operand sort of each group's packed key (``key_groups``, the
    entry's index the least significant field), the last group first."""
    perm = None
    for group in reversed(groups):
        packed = pack([codes[i] if perm is None else codes[i][perm] for i in group],
                      [bits[i] for i in group], idx_bits)
        with jax.enable_x64(packed.dtype == jnp.int64):
            packed = jax.lax.sort(packed, is_stable=False)
            pos = (packed & ((1 << idx_bits) - 1)).astype(jnp.int32)
        perm = pos if perm is None else perm[pos]
        if len(groups) == 1:  # the sorted keys are in the packed key already
            out_keys = unpack(packed, [bits[i] for i in group], idx_bits, limits)
    if len(groups) > 1:
        out_keys = [jnp.where(c[perm] > lim, EMPTY, c[perm]) for c, lim in zip(codes, limits)]
    return out_keys, [p[perm] for p in payloads]


def pair_sort(codes, bits, limits, payloads):
    """``lex_sort`` of keys that fit one uint64 (or uint32) without the entry's index but not
    one int64 (int32) beside it: one stable sort of the packed key carrying the index as its
    second operand (ties in index order, as the index's place in ``pack`` gives them). On an
    H100 with jax 0.11 XLA compiles this sort (an unsigned key, the index beside it) to cub's
    pairs radix sort, one call where the packed int64 keys took one cub keys sort each
    (RESULTS.md)."""
    packed = pack(codes, bits, 0, unsigned=True)
    with jax.enable_x64(True):
        index = jnp.arange(packed.shape[0], dtype=jnp.int32)
        packed, perm = jax.lax.sort((packed, index), num_keys=1, is_stable=True)
    return unpack(packed, bits, 0, limits), [p[perm] for p in payloads]


def key_groups(bits: Sequence[int], room: int) -> list[list[int]]:
    """Consecutive keys packed together, each group at most ``room`` bits (the last key of a
    group the least significant); the least significant keys fill their group first."""
    groups, width = [[]], 0
    for i in reversed(range(len(bits))):
        if groups[0] and width + bits[i] > room:
            groups.insert(0, [])
            width = 0
        groups[0].insert(0, i)
        width += bits[i]
    return groups


def pack(codes: Sequence[Array], bits: Sequence[int], idx_bits: int,
         unsigned: bool = False) -> Array:
    """(code_0 ... code_k, entry index) as one int32 or int64 (uint32 or uint64 if
    ``unsigned``), code_0 most significant; ``idx_bits`` 0: no index."""
    total = sum(bits) + idx_bits
    if unsigned:
        wide = jnp.uint32 if total <= 32 else jnp.uint64
    else:
        wide = jnp.int32 if total <= 31 else jnp.int64
    with jax.enable_x64(jnp.dtype(wide).itemsize == 8):
        packed = jnp.zeros(codes[0].shape, wide)
        for code, b in zip(codes, bits):
            packed = (packed << b) | code.astype(wide)
        if not idx_bits:
            return packed
        return (packed << idx_bits) | jnp.arange(codes[0].shape[0], dtype=wide)


def unpack(packed: Array, bits: Sequence[int], idx_bits: int, limits) -> list[Array]:
    """The int32 keys of a sorted ``pack``, EMPTY where a code is past its limit."""
    out, shift = [], sum(bits) + idx_bits
    with jax.enable_x64(packed.dtype.itemsize == 8):
        for lim, b in zip(limits, bits):
            shift -= b
            v = ((packed >> shift) & ((1 << b) - 1)).astype(jnp.int32)
            out.append(jnp.where(v > lim, EMPTY, v))
    return out


# The prefix lengths ``lex_sort_prefix`` sorts, as fractions of the list: a fragment list's
# capacity is a few times what a frame fills, and a radix sort costs what it sorts.
PREFIX_FRACTIONS = (1 / 8, 3 / 16, 1 / 4, 3 / 8, 1 / 2, 3 / 4)


def prefix_sizes(n: int) -> list[int]:
    """The static prefix lengths ``lex_sort_prefix`` chooses from for a list of ``n``."""
    return sorted({max(1, -(-n * int(f * 16) // 16)) for f in PREFIX_FRACTIONS} | {n})


def prefix_branch(count: Array, sizes: Sequence[int]) -> Array:
    """The index of the shortest of ``sizes`` (ascending, the last the whole list) that holds
    ``count`` entries: the branch a prefix switch takes."""
    return sum((jnp.asarray(count) > m).astype(jnp.int32) for m in sizes[:-1])


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

    which = prefix_branch(count, sizes)
    return jax.lax.switch(which, [sort_first(m) for m in sizes], (keys, list(payloads)))


def on_prefix(fn, count: Array, rows, whole=None, fill=False):
    """``fn(rows cut to their first m entries, whole) -> (row results, other results)`` for the
    shortest m of ``prefix_sizes`` that holds ``count`` (int32, traced) entries: for work over
    a list whose entries at and past ``count`` are empty, so that it costs what the list
    holds, not its capacity (one ``lax.switch``, one branch per size). Row results come back
    padded to the full length with ``fill`` (a scalar, or a pytree of scalars matching the row
    results); ``fn`` must give an empty entry the result ``fill`` for the answer not to depend
    on m."""
    n = jax.tree_util.tree_leaves(rows)[0].shape[0]
    sizes = prefix_sizes(n)

    def cut(m: int):
        def branch(operands):
            part, rest = operands
            out_rows, out_rest = fn(jax.tree_util.tree_map(lambda a: a[:m], part), rest)
            fills = (jax.tree_util.tree_map(lambda _: fill, out_rows)
                     if not isinstance(fill, (tuple, list, dict)) else fill)
            padded = jax.tree_util.tree_map(
                lambda a, f: jnp.concatenate([a, jnp.full((n - m,) + a.shape[1:], f, a.dtype)]),
                out_rows, fills)
            return padded, out_rest
        return branch

    which = prefix_branch(count, sizes)
    return jax.lax.switch(which, [cut(m) for m in sizes], (rows, whole))
