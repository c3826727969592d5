"""The temporal metrics a study selects by name: warp_error (with the sequence's motion field)
and mean_flip, beside temporal_error; neither is computed unasked."""

import numpy as np
import pytest

from jaxrender import metrics
from jaxrender.metrics.temporal import warp_error
from jaxrender.scene.reprojection import Reprojection
from jaxrender.study import backend
from jaxrender.study.specs import Study

T, H, W = 3, 20, 24


def _sequences(rng):
    ref = rng.uniform(0.1, 0.9, (T, H, W, 3)).astype(np.float32)
    test = np.clip(ref + rng.normal(0, 0.05, ref.shape), 0, 1).astype(np.float32)
    return test, ref


def test_mean_flip_is_the_mean_of_each_frames_flip(rng):
    test, ref = _sequences(rng)
    got, per_frame = backend.sequence_metrics(test, ref, ["mean_flip", "psnr"])
    dt, dr = metrics.to_display(test), metrics.to_display(ref)
    want = np.mean([float(np.asarray(metrics.flip(dr[i], dt[i])[0])) for i in range(T)])
    assert set(got) == {"mean_flip"}
    np.testing.assert_allclose(got["mean_flip"], want, rtol=1e-5, err_msg="mean_flip")
    assert np.all(np.isnan(per_frame)), "no temporal_error asked: no per-frame values"


def test_warp_error_takes_the_motion_field(rng):
    test, ref = _sequences(rng)
    pos = rng.uniform(0, W, (T - 1, H, W, 2)).astype(np.float32)
    valid = rng.uniform(size=(T - 1, H, W)) > 0.3
    motion = Reprojection(pos, valid, np.zeros((T - 1, H, W), np.float32))
    got, _ = backend.sequence_metrics(test, ref, ["warp_error", "temporal_error"], motion)
    want = warp_error(metrics.to_display(test), metrics.to_display(ref), motion).relative
    np.testing.assert_allclose(got["warp_error"], float(want), rtol=1e-6, err_msg="warp_error")
    assert np.isfinite(got["temporal_error"])
    with pytest.raises(ValueError, match="motion field"):
        backend.sequence_metrics(test, ref, ["warp_error"])
    assert backend.needs_motion(["psnr", "warp_error"]) and not backend.needs_motion(["psnr"])


def test_new_metrics_are_selectable_but_not_default():
    assert {"warp_error", "mean_flip", "temporal_error"} <= set(metrics.METRICS)
    assert "warp_error" not in metrics.DEFAULT_METRICS
    assert "mean_flip" not in metrics.DEFAULT_METRICS
    assert "temporal_error" in metrics.DEFAULT_METRICS
    assert Study.__dataclass_fields__["metrics"].default == metrics.DEFAULT_METRICS


def test_warp_error_test_is_finite_where_the_reference_stands_still(rng):
    # A still reference: its own warping error is 0, so the relative warp_error is +inf for a
    # flickering test; warp_error_test is the test's own error, the numerator of that ratio.
    ref = np.repeat(rng.uniform(0.1, 0.9, (1, H, W, 3)).astype(np.float32), T, axis=0)
    test = np.clip(ref + rng.normal(0, 0.05, ref.shape), 0, 1).astype(np.float32)
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32) + 0.5  # pixel centres
    still = np.broadcast_to(np.stack([xs, ys], -1), (T - 1, H, W, 2)).copy()
    motion = Reprojection(still, np.ones((T - 1, H, W), bool), np.zeros((T - 1, H, W),
                                                                         np.float32))
    got, _ = backend.sequence_metrics(test, ref, ["warp_error", "warp_error_test"], motion)
    want = warp_error(metrics.to_display(test), metrics.to_display(ref), motion)
    assert got["warp_error"] == np.inf, got
    assert float(want.reference) == 0.0, "the still reference changed"
    np.testing.assert_allclose(got["warp_error_test"], float(want.test), rtol=1e-6,
                               err_msg="warp_error_test is not the test's warping error")
    assert np.isfinite(got["warp_error_test"]) and got["warp_error_test"] > 0.0
    assert "warp_error_test" not in metrics.DEFAULT_METRICS
