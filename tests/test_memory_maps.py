"""Compiled programs are freed once a process is past its share of the mapping limit."""

import jax
import jax.numpy as jnp
import pytest

from jaxrender import memory_maps

pytestmark = pytest.mark.skipif(memory_maps.mapped_regions() is None,
                                reason="no /proc/self/maps on this system")


def _program(seed: int):
    # Distinct programs of a few kernels each (a sort keeps them from fusing into one).
    @jax.jit
    def f(x):
        return jnp.sort(jnp.sin(x) * seed + jnp.cumsum(x))[::2].sum() + jnp.max(x * x)

    f(jnp.arange(64.0 + seed)).block_until_ready()
    return f


def _limit(monkeypatch, tmp_path, value: int):
    path = tmp_path / "max_map_count"
    path.write_text(f"{value}\n")
    monkeypatch.setattr(memory_maps, "MAP_COUNT_FILE", path)


def test_past_the_share_every_unheld_program_is_freed(monkeypatch, tmp_path):
    _program(0)  # what the first compile of a process maps once
    memory_maps.release()
    before = memory_maps.mapped_regions()
    held = _program(1)
    for seed in range(2, 80):
        _program(seed)  # compiled, then dropped by the caller: jax's cache keeps it
    grown = memory_maps.mapped_regions()
    added = grown - before
    # Other allocations map and unmap a few dozen regions as they like: compare with margins.
    assert added > 118, f"79 programs of a few kernels each map regions: {before} -> {grown}"
    _limit(monkeypatch, tmp_path, 10 ** 7)
    assert not memory_maps.release_if_crowded(now=True), "far under the limit: nothing to do"
    assert held._cache_size() == 1, "nothing released: the compiled program is still cached"
    _limit(monkeypatch, tmp_path, grown)  # half of it is passed
    assert memory_maps.release_if_crowded(now=True)
    assert held._cache_size() == 0, "released: jax's caches were dropped"
    after = memory_maps.mapped_regions()
    assert after < grown - added // 2, f"the dropped programs' regions are unmapped: {before} " \
        f"-> {grown} -> {after}"
    assert float(held(jnp.arange(65.0))) == pytest.approx(float(_program(1)(jnp.arange(65.0))))


def test_counts_at_most_every_recount_interval(monkeypatch, tmp_path):
    _limit(monkeypatch, tmp_path, 2)  # always crowded
    assert memory_maps.release_if_crowded(now=True)
    assert not memory_maps.release_if_crowded(), "counted just now: answered from that count"
    monkeypatch.setattr(memory_maps, "RECOUNT_S", 0.0)
    assert memory_maps.release_if_crowded()


def test_no_limit_to_read_means_nothing_to_do(monkeypatch, tmp_path):
    monkeypatch.setattr(memory_maps, "MAP_COUNT_FILE", tmp_path / "missing")
    assert memory_maps.map_limit() is None
    assert not memory_maps.release_if_crowded(now=True)


def test_only_the_main_thread_releases(monkeypatch, tmp_path):
    import threading

    _limit(monkeypatch, tmp_path, 2)  # always crowded
    seen = []
    worker = threading.Thread(target=lambda: seen.append(memory_maps.release_if_crowded(now=True)))
    worker.start()
    worker.join()
    assert seen == [False], "a study's loader thread leaves the caches alone"
    assert memory_maps.release_if_crowded(now=True)
