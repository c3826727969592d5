"""Metrics on the catalogue's metric inputs (constant, black, identical, HDR 1e4): never NaN.

Agreement with the oracle libraries on constant, black, identical, HDR-above-1 and 1-pixel-wide
images is pinned in tests/metrics/test_edge_cases.py; this adds HDR at 1e4 and checks every
metric, LDR and HDR, plus the temporal error, in one sweep over ``metric_cases``."""

import math

import numpy as np
import pytest

from jaxrender import metrics
from jaxrender.scene.hard_cases import metric_cases

CASES = metric_cases()


def _values(test, ref) -> dict:
    out = {k: float(np.asarray(v)) for k, v in metrics.image_metrics(test, ref).items()}
    out["flip_hdr"] = float(np.asarray(metrics.flip(ref, test, "hdr")[0]))
    out["temporal_error"] = float(np.asarray(
        metrics.temporal_error(np.stack([test, test]), np.stack([ref, ref]))))
    return out


@pytest.mark.parametrize("name", sorted(CASES))
def test_metrics_are_never_nan_and_inf_only_as_psnr_of_equal_images(name):
    test, ref = CASES[name]
    vals = _values(test, ref)
    assert not any(math.isnan(v) for v in vals.values()), vals
    equal_display = vals["mse"] == 0.0
    for k, v in vals.items():
        if k == "psnr" and equal_display:
            assert v == math.inf, (k, v)
        else:
            assert math.isfinite(v), (name, k, v)


def test_hdr_1e4_is_saturated_on_a_display_and_distinct_in_hdr():
    test, ref = CASES["hdr_1e4"]
    vals = _values(test, ref)
    # Both clamp to white on the display: equal there; HDR-FLIP still sees the difference.
    assert vals["mse"] == 0.0 and vals["psnr"] == math.inf and vals["flip"] == 0.0
    assert vals["flip_hdr"] > 0.0
    vals = _values(*CASES["hdr_vs_black"])
    assert vals["rmse"] == pytest.approx(1.0) and 0.0 < vals["flip_hdr"] <= 1.0
