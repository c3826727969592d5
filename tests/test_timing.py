"""The shared timing helpers: what they call, how often, and what they hand back."""

import jax.numpy as jnp

from jaxrender import timing


def test_time_interleaved_threads_each_steps_state():
    calls = {"a": 0, "b": 0}

    def step(name, inc):
        def run(state):
            calls[name] += 1
            return (jnp.int32(0) if state is None else state) + inc
        return run

    medians, last = timing.time_interleaved({"a": step("a", 1), "b": step("b", 2)}, repeats=6,
                                            rounds=3, warmup=2)
    per_step = 2 + 3 * (6 // 3)  # warm-up, then rounds x calls per round
    assert calls == {"a": per_step, "b": per_step}
    assert (int(last["a"]), int(last["b"])) == (per_step, 2 * per_step)
    assert set(medians) == {"a", "b"} and all(m >= 0 for m in medians.values())


def test_time_batched_and_sample_stats():
    n = []
    ms = timing.time_batched(lambda x: n.append(1) or x + 1, jnp.ones(3), calls=4, repeats=2)
    assert len(n) == 2 * (1 + 4) and ms >= 0  # one wait-for call, then the batch, per repeat
    assert timing.sample_stats([3.0, 1.0, 2.0]) == {"median_ms": 2.0, "min_ms": 1.0,
                                                    "max_ms": 3.0, "repeats": 3}
