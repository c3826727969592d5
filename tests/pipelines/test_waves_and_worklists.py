"""The shared work-list dispatch and wave counts: counts read off the work list, waves against
a plain loop over groups, and the 8x8-tile grouping against its definition."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.pipelines import dispatch
from jaxrender.pipelines.waves import (count_waves, group_sizes, segment_lanes, tile_rows,
                                      tile_waves)


def test_worklist_counts_come_from_the_dispatch(rng):
    active = rng.random(300) < 0.3
    work = dispatch.WorkList.of(jnp.asarray(active))
    n = int(active.sum())
    assert int(work.count) == n
    np.testing.assert_array_equal(np.asarray(work.items)[:n], np.nonzero(active)[0])
    out, done = dispatch.run(work, lambda items, live: items.astype(jnp.float32) + 1.0,
                             jnp.zeros((300,), jnp.float32), 64)
    want = np.where(active, np.arange(300) + 1.0, 0.0)
    np.testing.assert_array_equal(np.asarray(out), want)
    chunks = -(-n // 64)
    assert (int(done.invocations), int(done.chunks), int(done.lanes)) == (n, chunks, chunks * 64)
    assert int(done.idle_lanes) == chunks * 64 - n
    assert done.counts == {"invocations": done.invocations, "lanes": done.lanes,
                           "chunks": done.chunks}


def _chunks_launched(mode: str, n: int, chunk: int) -> int:
    # Hand-worked: the loop and the bit decomposition launch ceil(n / chunk) chunks, the switch
    # the next power of two of that (none for an empty list).
    whole = -(-n // chunk)
    if mode == "switch" and whole:
        return 1 << (whole - 1).bit_length()
    return whole


@pytest.mark.parametrize("mode", dispatch.LAUNCH_MODES)
@pytest.mark.parametrize("n_active", [0, 1, 63, 64, 65, 200, 300])
def test_every_launch_mode_writes_the_same_and_counts_its_lanes(rng, monkeypatch, mode,
                                                                n_active):
    monkeypatch.setenv(dispatch.ENV_LAUNCH, mode)
    active = np.zeros(300, bool)
    active[rng.choice(300, n_active, replace=False)] = True
    work = dispatch.WorkList.of(jnp.asarray(active))
    fn = lambda items, live: items.astype(jnp.float32) * 2.0 + 1.0  # noqa: E731
    out, done = dispatch.run(work, fn, jnp.full((300,), -1.0, jnp.float32), 64)
    np.testing.assert_array_equal(np.asarray(out), np.where(active, np.arange(300) * 2.0 + 1.0,
                                                            -1.0), err_msg=mode)
    chunks = _chunks_launched(mode, n_active, 64)
    assert (int(done.invocations), int(done.chunks), int(done.lanes)) == (
        n_active, chunks, chunks * 64), (mode, n_active)
    # Lanes not one-to-one with outputs: every other lane writes.
    lanes_fn = lambda lanes, live: (lanes // 2, lanes.astype(jnp.float32), lanes % 2 == 0)  # noqa
    out, done = dispatch.dispatch_lanes(jnp.int32(2 * n_active), lanes_fn,
                                        jnp.zeros((300,), jnp.float32), 64, 600)
    want = np.zeros(300)
    want[:n_active] = np.arange(n_active) * 2.0
    np.testing.assert_array_equal(np.asarray(out), want, err_msg=f"{mode} lanes")
    chunks = _chunks_launched(mode, 2 * n_active, 64)
    assert (int(done.invocations), int(done.chunks)) == (n_active, chunks), (mode, n_active)


def test_an_unknown_launch_mode_is_refused(monkeypatch):
    monkeypatch.setenv(dispatch.ENV_LAUNCH, "unrolled")
    with pytest.raises(ValueError, match="JAXRENDER_DISPATCH='unrolled'.*loop, blocks, switch, binary"):
        dispatch.launch_mode()


@pytest.mark.parametrize("wave_size", [32, 64])
def test_count_waves_is_a_ceiling_per_group(rng, wave_size):
    lanes = rng.integers(0, 200, 17)
    waves, util = count_waves(jnp.asarray(lanes, jnp.int32), wave_size, jnp.int32(1000))
    want = sum(-(-int(x) // wave_size) for x in lanes)
    assert int(waves) == want
    np.testing.assert_allclose(float(util), 1000 / (want * wave_size), rtol=1e-6)
    none, zero = count_waves(jnp.zeros((3,), jnp.int32), wave_size, jnp.int32(0))
    assert int(none) == 0 and float(zero) == 0.0


@pytest.mark.parametrize("wave_size", [32, 64])
def test_tile_waves_count_groups_of_tile_rows(rng, wave_size):
    h, w = 19, 27
    active = rng.random((h, w)) < 0.1
    rows = wave_size // 8  # tile rows per wave
    want = 0
    for ty in range(0, h, 8):
        for tx in range(0, w, 8):
            for g in range(8 // rows):
                block = active[ty + g * rows:ty + (g + 1) * rows, tx:tx + 8]
                want += int(block.any())
    got, _ = tile_waves(jnp.asarray(active), wave_size, jnp.int32(int(active.sum())))
    assert int(got) == want
    assert int(jnp.sum(tile_rows(jnp.asarray(active), wave_size))) == int(active.sum())


def test_segment_lanes():
    starts = jnp.asarray([True, False, True, True, False, False, True])
    live = jnp.asarray([True, True, True, True, True, False, False])
    np.testing.assert_array_equal(np.asarray(segment_lanes(starts, live)), [2, 1, 2, 0, 0, 0, 0])


def test_segment_lanes_counts_the_live_items_of_each_segment(rng):
    n = 5000
    starts = rng.random(n) < 0.02
    starts[0] = True
    live = rng.random(n) < 0.8  # not a prefix: every live item counts where it lies
    seg = np.cumsum(starts) - 1
    want = np.zeros(n, np.int64)
    want[: seg[-1] + 1] = np.bincount(seg[live], minlength=seg[-1] + 1)
    got = segment_lanes(jnp.asarray(starts), jnp.asarray(live))
    np.testing.assert_array_equal(np.asarray(got), want, err_msg="live items per segment")


@pytest.mark.parametrize("n_groups", [1, 3, 5000])
def test_group_sizes_is_a_histogram(rng, n_groups):
    group = rng.integers(0, n_groups, 20000)
    live = rng.random(20000) < 0.7
    got = group_sizes(jnp.asarray(group, jnp.int32), jnp.asarray(live), n_groups)
    np.testing.assert_array_equal(np.asarray(got), np.bincount(group[live], minlength=n_groups),
                                  err_msg=f"{n_groups} groups")


def test_packed_segmented_cummin_equals_the_scan(rng):
    """The GPU's packed-key running minimum against the CPU's scan and a NumPy loop, with
    negative depths, +inf and one-entry segments."""
    from jaxrender.pipelines.quads import packed_segmented_cummin, scan_segmented_cummin

    n = 5000
    values = rng.normal(size=n).astype(np.float32)
    values[rng.random(n) < 0.1] = np.inf
    start = rng.random(n) < 0.2
    start[0] = True
    want, run = np.empty(n, np.float32), np.inf
    for i in range(n):
        run = values[i] if start[i] else min(run, values[i])
        want[i] = run
    # Jitted as the pipelines run them: one compile each, not one per eager op of the scan.
    packed, scan = jax.jit(packed_segmented_cummin), jax.jit(scan_segmented_cummin)
    args = jnp.asarray(values), jnp.asarray(start)
    np.testing.assert_array_equal(np.asarray(packed(*args)), want,
                                  err_msg="packed-key segmented cummin")
    np.testing.assert_array_equal(np.asarray(scan(*args)), want,
                                  err_msg="scan segmented cummin")
    # Columns (forward's four quad lanes): each column its own running minimum, one segmentation.
    cols = np.stack([values, values[::-1], np.roll(values, 3)], axis=1)
    want_cols = np.stack([np.asarray(packed(jnp.asarray(c), args[1])) for c in cols.T], axis=1)
    for fn in (packed, scan):
        np.testing.assert_array_equal(np.asarray(fn(jnp.asarray(cols), args[1])), want_cols,
                                      err_msg=f"{fn} of three columns")


@dataclasses.dataclass
class IndexPoints:
    """The least a shader needs: each lane's flat index and whether it is valid."""
    index: jnp.ndarray
    valid: jnp.ndarray


def index_points(items):
    return IndexPoints(items, jnp.ones(items.shape, bool))


def odd_of_index(points):
    return jnp.where(points.valid, points.index.astype(jnp.float32) * 2 + 1, 0.0)


@pytest.mark.parametrize("tiers, n_active", [((2,), n) for n in (0, 1, 149, 150, 151, 300)]
                         + [((8, 4, 2), n) for n in (1, 37, 38, 74, 75, 76, 150, 151)])
def test_the_dense_launch_compacts_into_its_tiers_and_runs_more_in_place(rng, tiers, n_active):
    """One launch: the active entries compacted into the smallest tier (300 // d lanes) that
    holds them, every entry in place past the largest, nothing for none; the same values
    either way."""
    active = np.zeros(300, bool)
    active[rng.choice(300, n_active, replace=False)] = True
    out, done = dispatch.shade_dense(jnp.asarray(active), index_points, odd_of_index,
                                     jnp.full((300,), -1.0, jnp.float32), tiers)
    np.testing.assert_array_equal(np.asarray(out), np.where(active, np.arange(300) * 2.0 + 1.0,
                                                            -1.0), err_msg=f"{tiers} {n_active}")
    sizes = sorted(300 // d for d in tiers)  # 37, 75, 150 for (8, 4, 2)
    lanes = 0 if n_active == 0 else next((m for m in sizes if n_active <= m), 300)
    assert (int(done.invocations), int(done.chunks), int(done.lanes)) == (
        n_active, int(n_active > 0), lanes), (tiers, n_active)


@pytest.mark.parametrize("chunk, env, launches", [
    (0, "", "dense"), (64, "", "chunked"), (0, "loop", "chunked"), (0, "switch", "chunked")])
def test_a_screen_pass_is_one_dense_launch_unless_a_chunk_or_mode_is_named(
        rng, monkeypatch, chunk, env, launches):
    """Deferred's screen passes: with the auto chunk, one launch over SCREEN_TIERS; a chunk
    size or a JAXRENDER_DISPATCH mode given puts them back on the chunked dispatch, so that
    neither setting is accepted and ignored. The values are the same either way."""
    monkeypatch.setenv(dispatch.ENV_LAUNCH, env)
    n = 4096 + 300  # auto_chunk's smallest chunk is 4096: two chunks when chunked
    active = rng.random(n) < 0.2
    out, done = dispatch.shade_screen(jnp.asarray(active), index_points, odd_of_index,
                                      jnp.full((n,), -1.0, jnp.float32), chunk)
    np.testing.assert_array_equal(np.asarray(out), np.where(active, np.arange(n) * 2.0 + 1.0,
                                                            -1.0), err_msg=f"{chunk} {env!r}")
    assert int(done.invocations) == int(active.sum()), (chunk, env)
    if launches == "dense":
        size = next(n // d for d in sorted(dispatch.SCREEN_TIERS, reverse=True)
                    if active.sum() <= n // d)
        assert (int(done.chunks), int(done.lanes)) == (1, size), (chunk, env)
    else:
        size = dispatch.resolve_chunk(chunk, n)
        assert int(done.chunk) == size and int(done.lanes) % size == 0, (chunk, env, done.chunk)
        assert int(done.lanes) >= int(active.sum()), (chunk, env)


@pytest.mark.parametrize("chunk", [0, 64])
@pytest.mark.parametrize("share", [0.1, 0.3, 0.9])
def test_a_pass_writes_a_tuple_of_arrays_as_it_writes_one(rng, chunk, share):
    """The G-buffer is one array a field: a pass whose shader returns a tuple writes each
    array where it writes the one (compacted into a tier, in place, or chunked), with each
    array's own width and dtype, and leaves the other entries as they were."""
    n = 4096 + 300
    active = rng.random(n) < share
    out = (jnp.full((n, 3), -1.0, jnp.float32), jnp.full((n,), 7, jnp.int32))

    def fields(points):
        i = points.index
        return jnp.stack([i, 2 * i, 3 * i], axis=1).astype(jnp.float32), i + 1

    (wide, narrow), done = dispatch.shade_screen(jnp.asarray(active), index_points, fields, out,
                                                 chunk)
    i = np.arange(n)
    np.testing.assert_array_equal(
        np.asarray(wide), np.where(active[:, None], np.stack([i, 2 * i, 3 * i], 1), -1.0),
        err_msg=f"the [N, 3] field, chunk {chunk}, {share:.0%} active")
    np.testing.assert_array_equal(np.asarray(narrow), np.where(active, i + 1, 7),
                                  err_msg=f"the int32 field, chunk {chunk}, {share:.0%} active")
    assert narrow.dtype == jnp.int32 and int(done.invocations) == int(active.sum())


@pytest.mark.parametrize("tiers", [(1,), (4, 0)])
def test_the_dense_launch_refuses_a_tier_below_two(tiers):
    points_of = lambda items: None  # noqa: E731 - never reached
    with pytest.raises(ValueError, match=r"must be at least 2 .*got tiers="):
        dispatch.shade_dense(jnp.ones((8,), bool), points_of, points_of, jnp.zeros((8,)), tiers)


@pytest.mark.parametrize("pipeline", ["forward", "deferred", "visbuffer", "checkerboard",
                                      "object_space"])
def test_every_pipeline_checks_wave_size_one_way(pipeline):
    from jaxrender.pipelines import make_config

    assert make_config(pipeline, width=8, height=8, wave_size=64).wave_size == 64
    with pytest.raises(ValueError, match="^wave_size must be 32 or 64, got 48$"):
        make_config(pipeline, width=8, height=8, wave_size=48)


def test_blocks_is_the_default_and_the_variable_is_read_case_blind(monkeypatch):
    monkeypatch.delenv(dispatch.ENV_LAUNCH, raising=False)
    assert dispatch.launch_mode() == "blocks"
    monkeypatch.setenv(dispatch.ENV_LAUNCH, " Binary ")
    assert dispatch.launch_mode() == "binary"
