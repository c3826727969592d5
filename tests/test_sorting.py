"""lex_sort against NumPy's lexsort on fresh random keys, packed and unpacked paths."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.sorting import EMPTY, lex_sort


def random_keys(limits, n=3000):
    """Keys with ties in [0, limit] (the first 20% EMPTY) and a payload, as NumPy arrays."""
    rng = np.random.default_rng(len(limits) + limits[0] % 97)
    keys = [rng.integers(0, min(lim, 50) + 1, n).astype(np.int64) for lim in limits]
    keys[0][rng.random(n) < 0.2] = EMPTY  # unused entries: after every value
    return keys, rng.random((n, 2)).astype(np.float32)


def assert_lexsorted(got_keys, got_payload, keys, payload, path):
    order = np.lexsort(keys[::-1])  # stable, first key most significant
    for i, (g, k) in enumerate(zip(got_keys, keys)):
        np.testing.assert_array_equal(np.asarray(g), k[order], err_msg=f"{path}: key {i}")
    np.testing.assert_array_equal(np.asarray(got_payload), payload[order],
                                  err_msg=f"{path}: payload not carried in the stable order")


# At n = 3000 (12 index bits): (3, 100) and (7, 2**20, 2**17) pack beside the index;
# (2**24, 2**26, 2**5) and (2**20, 2**30) fit a uint64 only without it (``pair_sort`` on a
# GPU, several packed sorts elsewhere); the others need several packed sorts. NARROW_LIMITS
# (32 and 31 bits) fit a uint32 only without the index: a uint32 pairs sort on a GPU.
PAIR_LIMITS = [(2**24, 2**26, 2**5), (2**20, 2**30)]
NARROW_LIMITS = [(2**12, 2**14, 2**3), (2**13, 2**16)]


@pytest.mark.parametrize("limits", [(3, 100), (7, 2**20, 2**17), (2**31 - 2, 2**31 - 2, 5),
                                    (2**30,) * 4, *PAIR_LIMITS, *NARROW_LIMITS])
def test_lex_sort_equals_numpy_lexsort(limits):
    keys, payload = random_keys(limits)
    got_keys, (got_payload,) = lex_sort([jnp.asarray(k, jnp.int32) for k in keys], limits,
                                        [jnp.asarray(payload)])
    assert_lexsorted(got_keys, got_payload, keys, payload, "lex_sort")


@pytest.mark.parametrize("limits", PAIR_LIMITS + NARROW_LIMITS)
def test_pair_sort_equals_numpy_lexsort(limits):
    """The GPU's path, called directly: on this CPU ``lex_sort`` takes the packed sorts."""
    from jaxrender.sorting import key_codes, pair_sort

    keys, payload = random_keys(limits)
    codes, bits = key_codes(keys, limits)
    got_keys, (got_payload,) = pair_sort(codes, bits, limits, [jnp.asarray(payload)])
    assert_lexsorted(got_keys, got_payload, keys, payload, "pair_sort")


@pytest.mark.parametrize("limits, platform, operands, key_type", [
    (PAIR_LIMITS[1], "cuda", [2], "ui64"), (PAIR_LIMITS[1], "cpu", [1, 1], "i64"),
    (NARROW_LIMITS[1], "cuda", [2], "ui32"), (NARROW_LIMITS[1], "cpu", [1], "i64")])
def test_keys_wider_than_the_index_allows_sort_once_on_a_gpu(limits, platform, operands,
                                                             key_type):
    """Lowered for each platform: one sort of (key, index) for CUDA, its key a uint32 where
    the keys fit one; packed-key sorts of one operand each for the CPU (where the stable
    two-operand sort is a comparison sort)."""
    def fn(a, b):
        return lex_sort((a, b), limits)

    x = jnp.zeros(3000, jnp.int32)
    text = jax.jit(fn).trace(x, x).lower(lowering_platforms=(platform,)).as_text()
    sorts = re.findall(r'"stablehlo.sort"\(([^)]*)\)', text)
    assert [len(s.split(",")) for s in sorts] == operands, (platform, sorts)
    types = re.findall(r'"stablehlo.sort".*?\}\) : \(tensor<3000x(\w+)>', text, re.S)
    assert types and types[0] == key_type, (platform, types)


def test_key_groups_fill_from_the_least_significant_key():
    from jaxrender.sorting import key_groups

    assert key_groups([21, 30], 63 - 23) == [[0], [1]]  # 8M entries: pixel, depth
    assert key_groups([21, 30], 63 - 12) == [[0, 1]]
    assert key_groups([3, 31, 31, 5], 51) == [[0, 1], [2, 3]]
    assert key_groups([31, 31, 31], 31) == [[0], [1], [2]]


@pytest.mark.parametrize("count", [0, 1, 700, 750, 751, 2999, 3000])
def test_lex_sort_prefix_equals_the_full_sort(count):
    from jaxrender.sorting import lex_sort_prefix, prefix_sizes

    assert prefix_sizes(6000)[-1] == 6000 and 750 in prefix_sizes(6000)
    rng = np.random.default_rng(count)
    n, limits = 6000, (2**21 - 1, 2**17)
    keys = [rng.integers(0, 60, n).astype(np.int64) for _ in limits]
    keys[1][rng.random(n) < 0.1] = -1  # out of range inside the live part: sorts after its key
    for k in keys:  # the empty tail: every key out of range, as the contract says
        k[count:] = rng.choice([-1, EMPTY, 2**22], n - count)
    payload = rng.random(n).astype(np.float32)
    args = [jnp.asarray(k, jnp.int32) for k in keys], limits, [jnp.asarray(payload)]
    want_keys, (want_payload,) = lex_sort(*args)
    got_keys, (got_payload,) = lex_sort_prefix(*args, jnp.int32(count))
    for i, (g, w) in enumerate(zip(got_keys, want_keys)):
        np.testing.assert_array_equal(np.asarray(g), np.asarray(w), err_msg=f"key {i}, {count}")
    np.testing.assert_array_equal(np.asarray(got_payload), np.asarray(want_payload),
                                  err_msg=f"payload, count {count}")


@pytest.mark.parametrize("count", [0, 1, 750, 751, 4499, 4500, 4501, 6000])
def test_on_prefix_runs_the_shortest_prefix_that_holds_the_count(count):
    """A running sum over the live entries, against the same over the whole list (NumPy), and
    the prefix length the branch saw: the smallest of ``prefix_sizes`` at or above count."""
    from jaxrender.sorting import on_prefix, prefix_sizes

    n = 6000
    rng = np.random.default_rng(count)
    values = np.where(np.arange(n) < count, rng.integers(1, 9, n), 0).astype(np.int32)
    live = np.arange(n) < count

    def fn(rows, scale):
        m = rows["v"].shape[0]
        run = jnp.where(rows["live"], jnp.cumsum(rows["v"]), 0)
        return {"run": run, "live": rows["live"]}, (jnp.sum(rows["v"]) * scale, jnp.int32(m))

    out, (total, m) = on_prefix(fn, jnp.int32(count),
                                {"v": jnp.asarray(values), "live": jnp.asarray(live)},
                                jnp.int32(3), {"run": -1, "live": False})
    want_run = np.where(live, np.cumsum(values), 0)
    want_run[max(count, int(m)):] = -1  # past the prefix: the fill
    np.testing.assert_array_equal(np.asarray(out["run"]), want_run, err_msg=f"count {count}")
    np.testing.assert_array_equal(np.asarray(out["live"]), live, err_msg=f"count {count}")
    assert int(total) == 3 * int(values.sum()), count
    assert int(m) == min(s for s in prefix_sizes(n) if s >= count), (count, int(m))
