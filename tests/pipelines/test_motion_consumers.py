"""What motion vectors feed: checkerboard's reprojection and the temporal metrics' warp, on the
sliding striped quad (tests/pipelines/motion_scenes.py)."""

import functools

import numpy as np

from jaxrender.metrics.temporal import warp_error
from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines.motion_field import motion_field
from jaxrender.scene.camera_path import stack
from tests.pipelines.motion_scenes import CAMERA, H, W
from tests.pipelines.motion_scenes import sliding_scene as _scene

FRAMES = 3


def _cams():
    return stack([CAMERA] * FRAMES)


@functools.lru_cache(maxsize=None)
def _deferred():
    return np.asarray(get_pipeline("deferred").render_sequence(
        _scene(), _cams(), make_config("deferred", width=W, height=H)).image)


def test_checkerboard_reprojects_moving_objects_with_their_motion_vectors():
    cb = get_pipeline("checkerboard").render_sequence(
        _scene(), _cams(), make_config("checkerboard", width=W, height=H))
    full = _deferred()
    t = FRAMES - 1
    hist = np.asarray(cb.aux["history"][t])
    assert hist.sum() >= 50, "the sliding quad's missing pixels must come from history"
    err = np.abs(np.asarray(cb.image[t]) - full[t]).mean(-1)[hist].mean()
    still = np.abs(full[t - 1] - full[t]).mean(-1)[hist].mean()
    assert still > 0.02, "the stripes must move under the pixels"
    assert err < 0.1 * still, (f"history through motion vectors is off by {err:.4f}; a "
                               f"pixel's own previous colour is off by {still:.4f}")


def test_warp_error_follows_moving_objects():
    frames = _deferred()
    mf = motion_field(_scene(), _cams(), W, H)
    assert mf.position.shape == (FRAMES - 1, H, W, 2) and mf.valid.mean() > 0.8
    moved = warp_error(frames, frames, mf).test
    centres = np.stack(np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5), -1)
    still = warp_error(frames, frames, np.broadcast_to(centres, mf.position.shape), mf.valid).test
    assert float(still) > 1e-3, "the stripes must move under the pixels"
    assert float(moved) < 0.05 * float(still), (
        f"warp with motion vectors {float(moved):.5f} vs without {float(still):.5f}")
