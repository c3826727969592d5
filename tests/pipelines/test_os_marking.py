"""Chunk and shadel marking (object-space step 3) against a NumPy reference: many taps on one
chunk (the marking scatter's hard case), zero-weight taps and empty pixels."""

import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.os_marking import Taps, mark_chunks, mark_shadels, mark_slot_shadels
from jaxrender.pipelines.os_sheet import LANES


def test_marking_equals_numpy(rng):
    n_chunks, p, k = 257, 5000, 8
    # Half the taps read a handful of chunks (heavy repetition), half any even chunk (so that
    # odd chunks past 3 stay unmarked).
    chunk = np.where(rng.random((p, k)) < 0.5, rng.integers(0, 4, (p, k)),
                     2 * rng.integers(0, n_chunks // 2 + 1, (p, k))).astype(np.int32)
    lane = rng.integers(0, LANES, (p, k)).astype(np.int32)
    weight = np.where(rng.random((p, k)) < 0.3, 0.0, rng.random((p, k))).astype(np.float32)
    t = Taps(jnp.asarray(chunk), jnp.asarray(lane), jnp.asarray(weight),
             jnp.zeros((p,), jnp.float32))
    use = weight > 0
    want_c = np.zeros(n_chunks, bool)
    want_c[chunk[use]] = True
    want_s = np.zeros(n_chunks * LANES, bool)
    want_s[(chunk * LANES + lane)[use]] = True
    np.testing.assert_array_equal(np.asarray(mark_chunks(t, n_chunks)), want_c,
                                  err_msg="chunks read by a tap of non-zero weight")
    np.testing.assert_array_equal(np.asarray(mark_shadels(t, n_chunks)), want_s,
                                  err_msg="shadels read by a tap of non-zero weight")
    assert 0 < want_c.sum() < n_chunks  # both outcomes occur

    # The same shadels addressed by store slot: a random page table with some chunks unallocated
    # (their taps mark nothing), as object_space's counts read them.
    cap = 100
    page = np.full(n_chunks, -1, np.int32)
    page[rng.permutation(n_chunks)[:cap]] = rng.permutation(cap)
    want_slot = np.zeros(cap * LANES, bool)
    ok = use & (page[chunk] >= 0)
    want_slot[(page[chunk] * LANES + lane)[ok]] = True
    np.testing.assert_array_equal(np.asarray(mark_slot_shadels(t, jnp.asarray(page), cap)),
                                  want_slot, err_msg="shadels of allocated slots read by a tap")
    assert 0 < ok.sum() < use.sum()  # taps of allocated and of unallocated chunks both occur
