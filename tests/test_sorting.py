"""lex_sort against NumPy's lexsort on fresh random keys, packed and unpacked paths."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.sorting import EMPTY, lex_sort


@pytest.mark.parametrize("limits", [(3, 100), (7, 2**20, 2**17), (2**24, 2**26, 2**5),
                                    (2**31 - 2, 2**31 - 2, 5)])
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
