"""Several samples in one traversal (``sample_visibility`` with offsets [S, 2]): each sample's
buffer must be the one it gets alone, bit for bit, on every traversal, with clipped triangles,
a keep filter, dead samples and chunks far smaller than the work; its box is the union of the
samples' boxes, so it lists fewer work items than the samples one by one."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster.rasterize import sample_visibility
from tests.raster.conftest import gl_clip, pad
from tests.raster.test_exact import H, W, _random_scene

FIELDS = ("tri_id", "depth", "bary", "dbary_dx", "dbary_dy")


def _clipped_scene(rng):
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 1, 300)  # some triangles cross the near plane
    return pad(gl_clip(p, aspect=W / H), np.arange(300).reshape(-1, 3).astype(np.int32))


def _keep_odd(chunk):
    return chunk.tri % 2 == 1, jnp.sum(chunk.covered)


def _keep_odd_many(chunk):
    return (chunk.tri % 2 == 1)[None], jnp.sum(chunk.covered)


@functools.lru_cache(maxsize=None)
def _programs(traversal):
    """(many samples, one sample) programs of a traversal, shared by both scene kinds (padded
    to the same shapes): the compile is most of each case's time."""
    kw = dict(work_capacity=512, clip_capacity=7, traversal=traversal)

    @jax.jit
    def many(c, f, o, lv):
        return (sample_visibility(c, f, W, H, o, live=lv, **kw),
                sample_visibility(c, f, W, H, o, live=lv, keep=_keep_odd_many, **kw))

    @jax.jit
    def one(c, f, o):
        return (sample_visibility(c, f, W, H, o, **kw),
                sample_visibility(c, f, W, H, o, keep=_keep_odd, **kw))

    return many, one


@pytest.mark.parametrize("traversal", ["bbox", "recompute", "spans", "gpu"])
@pytest.mark.parametrize("kind", ["mixed_sizes", "clipped"])
def test_each_sample_equals_its_own_traversal(rng, traversal, kind):
    clip, faces = _clipped_scene(rng) if kind == "clipped" else _random_scene(rng, kind)
    n = 5
    offsets = rng.integers(0, 256, (n, 2)).astype(np.int32)
    live = np.ones(n, bool)
    live[rng.integers(n)] = False
    offsets[~live] = offsets[live][0]  # a dead sample repeats a live one's offset
    many, one = _programs(traversal)
    c, f = jnp.asarray(clip), jnp.asarray(faces)
    (vis, counts), (odd, odd_counts) = many(c, f, jnp.asarray(offsets), jnp.asarray(live))
    fragments, items = 0, 0
    for s in range(n):
        (want, want_counts), (want_odd, _) = one(c, f, jnp.asarray(offsets[s]))
        for name in FIELDS:
            got = np.asarray(getattr(vis, name))[s]
            got_odd = np.asarray(getattr(odd, name))[s]
            if live[s]:
                np.testing.assert_array_equal(got, np.asarray(getattr(want, name)),
                                              err_msg=f"{traversal}, sample {s}: {name}")
                np.testing.assert_array_equal(got_odd, np.asarray(getattr(want_odd, name)),
                                              err_msg=f"{traversal}, sample {s}, kept: {name}")
        if live[s]:
            fragments += int(want_counts["fragments"])
            items += int(want_counts["work_items"])
        else:
            assert np.all(np.asarray(vis.tri_id)[s] == -1), f"dead sample {s} covers pixels"
    assert fragments > 0
    assert int(counts["fragments"]) == int(odd_counts["fragments"]) == fragments
    assert int(counts["clipped"]) == int(want_counts["clipped"])
    assert 0 < int(counts["work_items"]) < items, (int(counts["work_items"]), items)


@pytest.mark.parametrize("traversal", ["bbox", "recompute", "gpu"])
def test_one_fragment_list_for_several_samples(rng, traversal):
    """Sample s of pixel p is listed as pixel s * W * H + p; each live sample's fragments are
    its own list's, in its order; a dead sample lists nothing."""
    from jaxrender.raster.fragments import collect_fragments

    clip, faces = _clipped_scene(rng)
    offsets = rng.integers(0, 256, (4, 2)).astype(np.int32)
    offsets[2] = offsets[0]
    live = np.asarray([True, True, False, True])
    cap = 64 * W * H
    run = jax.jit(lambda c, f, o, lv: collect_fragments(
        c, f, W, H, cap, False, o, 512, 7, traversal, live=lv))
    c, f = jnp.asarray(clip), jnp.asarray(faces)
    many = run(c, f, jnp.asarray(offsets), jnp.asarray(live))
    n = int(many.count)
    pixel = np.asarray(many.pixel)[:n]
    total = 0
    for s in range(4):
        one = run(c, f, jnp.asarray(offsets[s]), None)
        mine = pixel // (W * H) == s
        if not live[s]:
            assert not mine.any(), f"dead sample {s} listed fragments"
            continue
        m = int(one.count)
        total += m
        assert m > 0 and int(mine.sum()) == m, (s, m, int(mine.sum()))
        np.testing.assert_array_equal(pixel[mine] % (W * H), np.asarray(one.pixel)[:m],
                                      err_msg=f"sample {s}: pixels")
        for name in ("tri", "depth"):
            np.testing.assert_array_equal(np.asarray(getattr(many, name))[:n][mine],
                                          np.asarray(getattr(one, name))[:m],
                                          err_msg=f"sample {s}: {name}")
    assert n == total
