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
