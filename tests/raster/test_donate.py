"""A frame loop's ``donate=``: the previous result's buffers become this call's output. The
values must be those of a plain call whatever the donated buffers held; the donated result is
spent; a mismatched buffer, or a donation inside jit, is refused with a message."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster import rasterize_clip, rasterize_depth_clip, samples
from jaxrender.types import DepthBuffer
from tests.raster.test_exact import H, W, _random_scene


def _values(buf):
    # Copies, so that no view of a device buffer outlives the buffer's donation.
    fields = ("tri_id", "depth") + (("bary",) if hasattr(buf, "bary") else ())
    return {f: np.array(getattr(buf, f), copy=True) for f in fields} | {
        k: int(v) for k, v in buf.counts.items()}


@pytest.mark.parametrize("entry", [rasterize_clip, rasterize_depth_clip])
@pytest.mark.parametrize("msaa", [False, True])
def test_donated_frames_equal_plain_calls(rng, entry, msaa):
    offsets = samples.msaa(4) if msaa else None
    clip, faces = _random_scene(rng, "mixed_sizes")
    # The second scene pushes depth past the near and far planes: clipped fans as well.
    scenes = [(clip, faces), (clip * np.float32([1.0, 1.0, 3.0, 1.0]), faces[::-1].copy())]
    want = [_values(entry(c, f, W, H, sample_offsets=offsets)) for c, f in scenes]
    frame = entry(*scenes[1], W, H, sample_offsets=offsets)
    for k in range(4):  # alternate scenes: each frame overwrites what the other one left
        previous = frame
        where = [leaf.unsafe_buffer_pointer() for leaf in jax.tree_util.tree_leaves(previous)]
        frame = entry(*scenes[k % 2], W, H, sample_offsets=offsets, donate=previous)
        assert previous.tri_id.is_deleted(), "the donated result should be spent"
        assert [leaf.unsafe_buffer_pointer() for leaf in jax.tree_util.tree_leaves(frame)] \
            == where, f"frame {k}: the outputs should occupy the donated buffers"
        got = _values(frame)
        assert k % 2 == 0 or got["clipped"] > 0, "the second scene should clip"
        for key, value in want[k % 2].items():
            np.testing.assert_array_equal(got[key], value,
                                          err_msg=f"{entry.__name__} frame {k}: {key}")


def test_bad_donations_are_refused(rng):
    clip, faces = _random_scene(rng, "mixed_sizes")
    depth = rasterize_depth_clip(clip, faces, W, H)
    with pytest.raises(ValueError, match="donate must be a VisBuffer"):
        rasterize_clip(clip, faces, W, H, donate=depth)
    with pytest.raises(ValueError, match=r"donate must be a DepthBuffer of shape \(4,"):
        rasterize_depth_clip(clip, faces, W, H, sample_offsets=samples.msaa(4), donate=depth)
    with pytest.raises(ValueError, match="got ndarray"):
        rasterize_depth_clip(clip, faces, W, H, donate=np.zeros((H, W)))
    with pytest.raises(ValueError, match=r"DepthBuffer of shape \(48, 64\)"):  # counts: a dict
        rasterize_depth_clip(clip, faces, W, H,
                             donate=dataclasses.replace(depth, counts=dict(depth.counts)))
    with pytest.raises(ValueError, match="share an array"):
        rasterize_depth_clip(clip, faces, W, H, donate=DepthBuffer(
            depth.tri_id, depth.tri_id, depth.counts))
    assert not depth.tri_id.is_deleted(), "a refused donation must leave the buffer alone"
    with pytest.raises(ValueError, match="inside jax.jit"):
        jax.jit(lambda c: rasterize_depth_clip(c, faces, W, H, donate=depth).depth)(clip)
    rasterize_depth_clip(clip, faces, W, H, donate=depth)
    with pytest.raises(ValueError, match="already gone"):
        rasterize_depth_clip(clip, faces, W, H, donate=depth)


def test_entry_points_nest_in_the_callers_programs(rng):
    """Device arrays closed over by a jit or scan body are not tracers, yet the call must
    join the caller's program (a top-level-only compiled entry may not be nested)."""
    clip, faces = (jnp.asarray(a) for a in _random_scene(rng, "mixed_sizes"))
    want = rasterize_depth_clip(clip, faces, W, H)
    got = jax.jit(lambda: rasterize_depth_clip(clip, faces, W, H))()
    np.testing.assert_array_equal(np.asarray(got.tri_id), np.asarray(want.tri_id),
                                  err_msg="jit: tri_id")
    # Closed-over geometry is a compile-time constant, and XLA folds part of the setup on the
    # host: on an H100 the depth of 704 of 3072 pixels moved by up to 5 ulp (2026-11-23; exact
    # on the CPU, and exact on both when the geometry is passed in as arguments).
    np.testing.assert_allclose(np.asarray(got.depth), np.asarray(want.depth), rtol=1e-6,
                               atol=0, err_msg="jit: depth")
    _, stacked = jax.lax.scan(lambda c, _: (c, rasterize_clip(clip, faces, W, H).tri_id),
                              0, None, length=2)
    np.testing.assert_array_equal(np.asarray(stacked)[1], np.asarray(want.tri_id),
                                  err_msg="inside lax.scan")
