"""``work_items.owners`` (each slot's first item marked, then a running maximum) against
np.searchsorted, on runs with many empty slots."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster import work_items


def _expected(count, base, capacity):
    incl = np.cumsum(count)
    item = base + np.arange(capacity)
    live = item < incl[-1]
    slot = np.minimum(np.searchsorted(incl, item, side="right"), len(count) - 1)
    return slot, item - (incl - count)[slot], live


@pytest.mark.parametrize("n_slots", [1, 7, 1000])
def test_owners_match_searchsorted(rng, n_slots):
    # Runs of 0 to 9 items, many empty (skipped slots), plus a few long runs.
    count = rng.integers(0, 10, n_slots) * (rng.random(n_slots) < 0.6)
    count[rng.integers(0, n_slots, max(1, n_slots // 100))] += rng.integers(50, 300)
    total, capacity = int(count.sum()), 64
    fn = jax.jit(lambda c, i, b: work_items.owners(c, i, b, capacity))
    with jax.enable_x64(True):
        incl = jnp.cumsum(jnp.asarray(count, jnp.int64))
        for base in sorted({0, 1, total // 3, max(total - capacity // 2, 0), total}):
            slot, j, live = (np.asarray(a) for a in fn(jnp.asarray(count, jnp.int32), incl,
                                                        jnp.int64(base)))
            want_slot, want_j, want_live = _expected(count, base, capacity)
            msg = f"{n_slots} slots, base {base}"
            np.testing.assert_array_equal(live, want_live, err_msg=msg + ": live")
            np.testing.assert_array_equal(slot[live], want_slot[want_live],
                                          err_msg=msg + ": slot")
            np.testing.assert_array_equal(j[live], want_j[want_live], err_msg=msg + ": j")
            assert np.all(j[live] >= 0) and np.all(j[live] < count[slot[live]]), msg
