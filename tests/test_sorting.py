"""lex_sort against NumPy's lexsort on fresh random keys, packed and unpacked paths."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.sorting import EMPTY, lex_sort


@pytest.mark.parametrize("limits", [(3, 100), (7, 2**20, 2**17), (2**24, 2**26, 2**5),
                                    (2**31 - 2, 2**31 - 2, 5), (2**30,) * 4, (2**20, 2**30)])
def test_lex_sort_equals_numpy_lexsort(limits):
    rng = np.random.default_rng(len(limits) + limits[0] % 97)
    n = 3000
    keys = [rng.integers(0, min(lim, 50) + 1, n).astype(np.int64) for lim in limits]
    keys[0][rng.random(n) < 0.2] = EMPTY  # unused entries: after every value
    payload = rng.random((n, 2)).astype(np.float32)
    got_keys, (got_payload,) = lex_sort([jnp.asarray(k, jnp.int32) for k in keys], limits,
                                        [jnp.asarray(payload)])
    order = np.lexsort(keys[::-1])  # stable, first key most significant
    for i, (g, k) in enumerate(zip(got_keys, keys)):
        np.testing.assert_array_equal(np.asarray(g), k[order], err_msg=f"key {i} differs")
    np.testing.assert_array_equal(np.asarray(got_payload), payload[order],
                                  err_msg="payload not carried in the stable order")


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
