"""The read counter against programs whose reads are known: a loop of k iterations reads k + 1
conditions, a cond one, a platform's choice none; and the dispatch's launch modes."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.bench import round_trips
from jaxrender.pipelines import dispatch


def _loop_then_cond(x, n):
    y = jax.lax.fori_loop(0, n, lambda i, a: a + i, x)
    return jax.lax.cond(y > 3.0, lambda a: a * 2.0, lambda a: a - 1.0, y)


@pytest.mark.parametrize("n", [0, 1, 5])
def test_a_loop_reads_its_condition_once_more_than_it_iterates(n):
    tally = round_trips.count(_loop_then_cond, jnp.float32(0.5), jnp.int32(n))
    kinds = {k: c for _, k, _, c in ((f, k, w, c) for (f, k, w), c in tally.reads.items())}
    assert tally.per_frame() == {None: n + 2}, tally.reads
    assert kinds == {"while": n + 1, "cond": 1}, kinds


def test_values_follow_the_program():
    tally = round_trips.Tally()
    closed = jax.make_jaxpr(_loop_then_cond)(jnp.float32(0.5), jnp.int32(4))
    got = round_trips.run_jaxpr(closed, [jnp.float32(0.5), jnp.int32(4)], tally)
    want = jax.jit(_loop_then_cond)(jnp.float32(0.5), jnp.int32(4))
    np.testing.assert_allclose(np.asarray(got[0]), np.asarray(want), rtol=0,
                               err_msg="the interpreter computed another value than jit")


def test_a_choice_by_platform_reads_nothing_and_follows_the_gpu():
    def f(x):
        return jax.lax.platform_dependent(x, cpu=lambda a: a + 1.0, default=lambda a: a + 10.0)

    tally = round_trips.Tally()
    closed = jax.make_jaxpr(f)(jnp.float32(1.0))
    (out,) = round_trips.run_jaxpr(closed, [jnp.float32(1.0)], tally)
    assert float(out) == 11.0, "the GPU (default) branch was not the one followed"
    assert sum(tally.reads.values()) == 0, tally.reads


def test_reads_are_kept_per_frame_of_the_outermost_scan():
    def f(ns):
        def frame(c, n):
            inner = jax.lax.scan(lambda a, _: (a + 1, None), c, None, length=3)[0]
            return jax.lax.fori_loop(0, n, lambda i, a: a + 1, inner), None
        return jax.lax.scan(frame, jnp.int32(0), ns)[0]

    tally = round_trips.count(f, jnp.array([2, 0, 4], jnp.int32))
    assert tally.per_frame() == {0: 3, 1: 1, 2: 5}, tally.per_frame()


@pytest.mark.parametrize("mode, n, chunk, want", [
    ("loop", 13, 4, 4 + 1), ("switch", 13, 4, 1), ("binary", 13, 4, 3),
    # blocks: a loop over 4-chunk blocks, then one over the chunks left (each read once more).
    ("blocks", 13, 4, (1 + 1) + (0 + 1)), ("blocks", 13, 1, (3 + 1) + (1 + 1)),
    ("blocks", 3, 1, (0 + 1) + (3 + 1)), ("loop", 13, 1, 13 + 1)])
def test_dispatch_reads_by_launch_mode(monkeypatch, mode, n, chunk, want):
    """The loop reads each chunk's condition and one more, the switch one branch index, the
    binary plan one per bit of the largest chunk count (16 items in 4: 3 bits)."""
    monkeypatch.setenv(dispatch.ENV_LAUNCH, mode)
    active = jnp.arange(16) < n

    def f(active):
        work = dispatch.WorkList.of(active)
        out, _ = dispatch.run(work, lambda items, live: items.astype(jnp.float32) + 1.0,
                              jnp.zeros((16,), jnp.float32), chunk)
        return out

    tally = round_trips.count(f, active)
    assert tally.per_frame() == {None: want}, (mode, tally.reads)
    closed = jax.make_jaxpr(f)(active)
    (out,) = round_trips.run_jaxpr(closed, [active], round_trips.Tally())
    np.testing.assert_array_equal(np.asarray(out), np.where(np.arange(16) < n,
                                                            np.arange(16) + 1.0, 0.0),
                                  err_msg=f"{mode}: the interpreted dispatch wrote wrong values")


def test_a_loop_inside_an_unfollowed_primitive_is_refused():
    """A primitive the counter does not follow (here custom_linear_solve) is bound whole; if
    it held a loop, its reads would go uncounted, so the count is refused instead."""

    def f(b):
        solve = lambda mv, r: jax.lax.while_loop(  # noqa: E731
            lambda a: a[1] < 3, lambda a: (a[0], a[1] + 1), (r / 2.0, 0))[0]
        return jax.lax.custom_linear_solve(lambda x: x * 2.0, b, solve=solve)

    closed = jax.make_jaxpr(f)(jnp.float32(1.0))
    assert "custom_linear_solve" not in round_trips.CALLS
    with pytest.raises(NotImplementedError, match="custom_linear_solve holds a loop"):
        round_trips.run_jaxpr(closed, [jnp.float32(1.0)], round_trips.Tally())
