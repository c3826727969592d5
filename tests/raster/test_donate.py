"""A frame loop's ``donate=``: the previous result's buffers become this call's output. The
values must be those of a plain call whatever the donated buffers held; the donated result is
spent; a mismatched buffer, or a donation inside jit, is refused with a message."""

import jax
import numpy as np
import pytest

from jaxrender.raster import rasterize_clip, rasterize_depth_clip, samples
from tests.raster.test_exact import H, W, _random_scene


def _values(buf):
    # Copies: on the CPU np.asarray would view the device buffer, and a buffer with a live
    # view cannot be donated.
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
        frame = entry(*scenes[k % 2], W, H, sample_offsets=offsets, donate=previous)
        assert previous.tri_id.is_deleted(), "the donated buffers should have been taken over"
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
    assert not depth.tri_id.is_deleted(), "a refused donation must leave the buffer alone"
    with pytest.raises(ValueError, match="inside jax.jit"):
        jax.jit(lambda c: rasterize_depth_clip(c, faces, W, H, donate=depth).depth)(clip)
