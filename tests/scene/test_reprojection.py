"""scene.reprojection is the camera math metrics.reproject checks and wraps: the same bits."""

import numpy as np
import pytest

from jaxrender import metrics
from jaxrender.scene.camera import look_at
from jaxrender.scene.reprojection import DEFAULT_DEPTH_TOLERANCE, Reprojection, reproject

W, H = 12, 8


def test_scene_reprojection_equals_the_metric(rng):
    cam = look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0))
    prev = look_at((0.2, 0.1, 3.1), (0.0, 0.0, 0.0))
    depth = rng.uniform(0.9, 0.99, (H, W)).astype(np.float32)
    prev_depth = rng.uniform(0.9, 0.99, (H, W)).astype(np.float32)
    got = reproject(depth, cam, prev, W, H, prev_depth=prev_depth)
    want = metrics.reproject(depth, cam, prev, W, H, prev_depth=prev_depth)
    assert isinstance(got, Reprojection) and metrics.Reprojection is Reprojection
    for g, w in zip(got, want):
        np.testing.assert_array_equal(np.asarray(g), np.asarray(w))
    assert DEFAULT_DEPTH_TOLERANCE == 0.01


def test_only_the_metric_refuses_nan():
    cam = look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0))
    depth = np.full((H, W), np.nan, np.float32)
    assert not np.asarray(reproject(depth, cam, cam, W, H).valid).any()
    with pytest.raises(ValueError, match="NaN"):
        metrics.reproject(depth, cam, cam, W, H)
    with pytest.raises(ValueError, match="depth must be"):
        reproject(depth, cam, cam, W + 1, H)
