"""compact_indices against NumPy's flatnonzero on fresh random masks."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.compaction import compact_indices


@pytest.mark.parametrize("n, p, size", [(1, 0.5, 1), (1000, 0.0, 1000), (1000, 1.0, 1000),
                                        (5000, 0.3, 5000), (5000, 0.7, 100)])
def test_compact_indices_equals_flatnonzero(n, p, size):
    rng = np.random.default_rng(n + int(p * 10) + size)
    mask = rng.random(n) < p
    idx, count = compact_indices(jnp.asarray(mask), size, fill_value=-7)
    want = np.flatnonzero(mask)
    assert int(count) == want.size, f"count {int(count)} != {want.size}"
    k = min(size, want.size)
    np.testing.assert_array_equal(np.asarray(idx[:k]), want[:k],
                                  err_msg="listed indices differ from flatnonzero")
    np.testing.assert_array_equal(np.asarray(idx[k:]), -7, err_msg="padding is not fill_value")


@pytest.mark.parametrize("start", [0, 37, 300, 10_000])
def test_compact_indices_window(start):
    # a loop lists the True entries `size` at a time: window [start, start + size) of them
    rng = np.random.default_rng(start)
    mask = rng.random(2000) < 0.4
    idx, count = compact_indices(jnp.asarray(mask), 64, fill_value=-1, start=jnp.int32(start))
    want = np.flatnonzero(mask)[start:start + 64]
    assert int(count) == int(mask.sum()), "count must be the total, whatever the window"
    np.testing.assert_array_equal(np.asarray(idx[:want.size]), want,
                                  err_msg=f"window at {start} differs from flatnonzero")
    np.testing.assert_array_equal(np.asarray(idx[want.size:]), -1,
                                  err_msg="padding is not fill_value")
