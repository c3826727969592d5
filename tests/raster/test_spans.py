"""The traversals must give the same VisBuffer bit for bit, and the same fragments in the same
order, on random scenes: spans (CPU default), bounding boxes with stored setup (CPU, small
frames) and bounding boxes with setup recomputed per item (GPU default)."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster import samples
from jaxrender.raster.fragments import fragments_jit
from jaxrender.raster.rasterize import rasterize_traced
from jaxrender.raster.samples import to_fixed
from jaxrender.raster.setup import SUBPIXEL_BITS
from tests.raster.conftest import gl_clip, pad
from tests.raster.test_exact import H, W, _random_scene

FIELDS = ("tri_id", "depth", "bary", "dbary_dx", "dbary_dy")


def _vis(clip, faces, traversal, *, cull=False, offsets=samples.CENTER, work=1 << 16, clip_cap=64):
    return rasterize_traced(
        jnp.asarray(clip), jnp.asarray(faces), width=W, height=H, cull_backfaces=cull,
        offsets=to_fixed(offsets, SUBPIXEL_BITS), work_capacity=work, clip_capacity=clip_cap,
        traversal=traversal,
    )


def _assert_same(a, b, what):
    for name in FIELDS:
        np.testing.assert_array_equal(
            np.asarray(getattr(a, name)), np.asarray(getattr(b, name)), err_msg=f"{what}: {name}"
        )
    assert {k: int(v) for k, v in a.counts.items()} == {k: int(v) for k, v in b.counts.items()}


@pytest.mark.parametrize("kind", ["mixed_sizes", "pixel_centres", "shared_edges"])
def test_spans_equal_bounding_boxes(rng, kind):
    clip, faces = _random_scene(rng, kind)
    cull = bool(rng.integers(2))
    ref = _vis(clip, faces, "bbox", cull=cull)
    for tr in ("spans", "recompute"):
        _assert_same(_vis(clip, faces, tr, cull=cull), ref, f"{kind}, {tr}")


def test_spans_equal_bounding_boxes_clipped_msaa_and_tiny_chunks(rng):
    # Near-plane crossings (clipped fans), 4 sample offsets, and chunks far smaller than the
    # work so that rows and pixels both run many chunks.
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 1, 300)
    clip, faces = pad(gl_clip(p, aspect=W / H), np.arange(300).reshape(-1, 3).astype(np.int32))
    pattern = samples.msaa(4)
    ref = _vis(clip, faces, "bbox", offsets=pattern)
    for work, clip_cap in ((1 << 16, 64), (512, 3)):
        for tr in ("spans", "recompute", "gpu"):
            got = _vis(clip, faces, tr, offsets=pattern, work=work, clip_cap=clip_cap)
            _assert_same(got, ref, f"{tr}, work={work}")


def test_spans_list_the_same_fragments_in_the_same_order(rng):
    clip, faces = _random_scene(rng, "mixed_sizes")
    cap = 16 * W * H

    out = {tr: fragments_jit(jnp.asarray(clip), jnp.asarray(faces), width=W, height=H,
                             capacity=cap, cull_backfaces=False, offset=(128, 128),
                             work_capacity=4096, clip_capacity=64, traversal=tr)
           for tr in ("bbox", "spans", "recompute", "gpu")}  # gpu: first chunk peeled alone
    n = int(out["bbox"].count)
    assert 0 < n <= cap
    for tr in ("spans", "recompute", "gpu"):
        assert int(out[tr].count) == n, tr
        for name in ("pixel", "tri", "depth"):
            a, b = getattr(out["bbox"], name), getattr(out[tr], name)
            np.testing.assert_array_equal(np.asarray(b)[:n], np.asarray(a)[:n],
                                          err_msg=f"{tr}: {name}")


def test_fragment_lists_of_clipped_triangles_in_small_chunks_match_the_boxes(rng):
    # The GPU's fragment traversal peels its first chunk alone, and so does each clip chunk's
    # coverage of its fans: with near-plane crossings and chunks far smaller than the work,
    # both run many chunks and clip chunks, and must list what the bounding boxes list.
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 1, 300)
    clip, faces = pad(gl_clip(p, aspect=W / H), np.arange(300).reshape(-1, 3).astype(np.int32))
    out = {tr: fragments_jit(jnp.asarray(clip), jnp.asarray(faces), width=W, height=H,
                             capacity=16 * W * H, cull_backfaces=False, offset=(128, 128),
                             work_capacity=512, clip_capacity=3, traversal=tr)
           for tr in ("bbox", "gpu")}
    n = int(out["bbox"].count)
    assert 0 < n <= 16 * W * H and int(out["gpu"].count) == n
    for name in ("pixel", "tri", "depth"):
        np.testing.assert_array_equal(np.asarray(getattr(out["gpu"], name))[:n],
                                      np.asarray(getattr(out["bbox"], name))[:n],
                                      err_msg=f"gpu against bbox: {name}")


@pytest.mark.parametrize("traversal", ["bbox", "recompute"])
def test_peeled_first_chunk_changes_nothing(rng, traversal):
    # The GPU runs a box traversal's first chunk outside its loop and the later chunks and the
    # ``then`` steps (the clip chunks) in one loop (peel=True), or in two (peel="first", the
    # fragment lists): the same chunks and steps, in the same order, must run, whether the
    # items fill many chunks, one, or none at all.
    import jax

    from jaxrender.raster.coverage import for_each_chunk
    from jaxrender.raster.work_items import Triangles, depth_key
    from jaxrender.raster.setup import SetupFn

    clip, faces = _random_scene(rng, "mixed_sizes")
    n = faces.shape[0]
    # One program per (capacity, peel), shared by its cases: the items' mask and the number of
    # further steps are arguments. (A fresh jit per case compiled 12 programs for these 4.)
    programs = {}

    def program(capacity, peel):
        if (capacity, peel) in programs:
            return programs[capacity, peel]

        def fn(st, c):
            zb, order = st
            pix = jnp.where(c.covered, c.py * W + c.px, W * H)
            # order-sensitive: a running hash of the covered items, chunk by chunk
            key = (c.tri.astype(jnp.int64) + 1) * (pix.astype(jnp.int64) + 7)
            h = jnp.sum(jnp.where(c.covered, key, 0))
            return zb.at[pix].min(depth_key(c.depth, c.tri), mode="drop"), order * 31 + h

        def then_body(k, carry):  # stands in for the clip chunks: order-sensitive too
            (zb, order), items = carry
            return (zb, order * 37 + k + 1), items + 10 * (k + 1)

        def chunks(t, m):
            init = (jnp.full((W * H,), (1 << 63) - 1, jnp.int64), jnp.int64(0))
            return for_each_chunk(t, SetupFn(W, H, False), capacity,
                                  jnp.asarray([128, 128], jnp.int64), init, fn, traversal,
                                  peel=peel, then=(m, then_body))

        programs[capacity, peel] = jax.jit(chunks)
        return programs[capacity, peel]

    def run(ok, capacity, peel, n_then):
        with jax.enable_x64(True):
            tris = Triangles(jnp.asarray(clip), jnp.asarray(faces), jnp.asarray(ok),
                             jnp.arange(n, dtype=jnp.int32))
            (zb, order), items = program(capacity, peel)(tris, jnp.int64(n_then))
            return np.asarray(zb), int(order), int(items)

    for ok, capacity in ((np.ones(n, bool), 256), (np.ones(n, bool), 1 << 20),
                         (np.zeros(n, bool), 256)):
        for n_then in (0, 3):
            a = run(ok, capacity, False, n_then)
            for peel in (True, "first"):
                b = run(ok, capacity, peel, n_then)
                what = f"peel={peel!r}, capacity {capacity}, {n_then} more steps"
                np.testing.assert_array_equal(b[0], a[0], err_msg=f"{what}: z-buffer")
                assert b[1:] == a[1:], (what, a[1:], b[1:])
    assert a[2] == 60  # the last case has no items (the peeled chunk was all masked): 10+20+30


def test_sample_visibility_is_the_rasterizers_per_sample_core(rng):
    """The public per-sample entry gives the rasterizer's VisBuffer; its ``keep`` filter
    discards fragments before the depth test (what lies behind them shows)."""
    import jax

    from jaxrender.raster.rasterize import sample_visibility

    clip, faces = _random_scene(rng, "mixed_sizes")
    (offset,) = to_fixed(samples.CENTER, SUBPIXEL_BITS)
    ref = _vis(clip, faces, "bbox")

    @jax.jit
    def run(c, f):
        keep_odd = lambda chunk: (chunk.tri % 2 == 1, jnp.sum(chunk.covered))  # noqa: E731
        args = (c, f, W, H, jnp.asarray(offset))
        kw = dict(work_capacity=1 << 16, clip_capacity=64, traversal="bbox")
        return sample_visibility(*args, **kw), sample_visibility(*args, keep=keep_odd, **kw)

    (vis, counts), (odd, odd_counts) = run(jnp.asarray(clip), jnp.asarray(faces))
    for name in FIELDS:
        np.testing.assert_array_equal(np.asarray(getattr(vis, name)),
                                      np.asarray(getattr(ref, name)), err_msg=name)
    assert int(counts["fragments"]) == int(ref.counts["fragments"])
    tri = np.asarray(odd.tri_id)
    assert np.all((tri == -1) | (tri % 2 == 1)) and np.any(tri >= 0)
    assert int(odd_counts["fragments"]) == int(counts["fragments"])  # counted before the test
    assert int(odd_counts["keep_tests"]) == int(counts["fragments"]), "tests keep said it ran"
    assert "keep_tests" not in counts


def test_an_unknown_peel_is_refused():
    from jaxrender.raster.coverage import PEELS, for_each_chunk

    with pytest.raises(ValueError, match="peel must be one of") as e:
        for_each_chunk(None, None, 64, None, None, None, "bbox", peel="frist")
    assert all(repr(p) in str(e.value) for p in PEELS), str(e.value)
