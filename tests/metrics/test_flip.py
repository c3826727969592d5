import flip_evaluator
import numpy as np
import pytest

from jaxrender import metrics
from jaxrender.metrics.flip import feature_taps, spatial_filter_radius, spatial_taps

MEAN_TOL = 1e-3  # issue 5: mean FLIP within 1e-3 of flip-evaluator
MAP_TOL = 1e-4  # per-pixel agreement of the error maps (float32 C++ vs our float32/float64)


def _oracle(ref, test, mode, parameters=None):
    """flip_evaluator.evaluate on private copies (it converts sRGB inputs in place) and with its
    sys.exit on bad arguments turned into a test failure."""
    r = np.ascontiguousarray(ref, dtype=np.float32).copy()
    t = np.ascontiguousarray(test, dtype=np.float32).copy()
    try:
        fmap, mean, _ = flip_evaluator.evaluate(r, t, mode, applyMagma=False,
                                                parameters=parameters or {})
    except SystemExit as e:  # pragma: no cover - only on a broken call
        pytest.fail(f"flip_evaluator exited: {e}")
    return float(mean), np.asarray(fmap).reshape(ref.shape[:2])


def _check(seeded, what, got, ref):
    got_mean, got_map = got
    ref_mean, ref_map = ref
    np.testing.assert_allclose(float(got_mean), ref_mean, rtol=0, atol=MEAN_TOL,
                               err_msg=seeded.msg(f"{what}: mean"))
    np.testing.assert_allclose(np.asarray(got_map), ref_map, rtol=0, atol=MAP_TOL,
                               err_msg=seeded.msg(f"{what}: map"))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_ldr_flip_matches_flip_evaluator(seeded, dtype):
    ref, test = seeded.pair(dtype=np.float32)
    got = metrics.flip(ref, test, dtype=dtype)
    assert got[0].dtype == dtype and got[1].shape == ref.shape[:2]
    _check(seeded, f"LDR {np.dtype(dtype).name}", got, _oracle(ref, test, "LDR"))


def test_ldr_flip_other_ppd(seeded):
    ref, test = seeded.pair((32, 40, 3), dtype=np.float32)
    got = metrics.flip(ref, test, ppd=30.0)
    _check(seeded, "LDR ppd=30", got, _oracle(ref, test, "LDR", {"ppd": 30.0}))


def test_hdr_flip_matches_flip_evaluator(seeded):
    ref, test = seeded.pair((32, 40, 3), dtype=np.float32)
    ref, test = ref * 8.0, test * 8.0  # HDR values well above 1
    _check(seeded, "HDR", metrics.flip(ref, test, "hdr"), _oracle(ref, test, "HDR"))
    # explicit exposure range and tone mapper
    params = {"startExposure": -3.0, "stopExposure": 1.0, "numExposures": 3,
              "tonemapper": "reinhard"}
    got = metrics.flip(ref, test, "hdr", start_exposure=-3.0, stop_exposure=1.0,
                       num_exposures=3, tonemapper="reinhard")
    _check(seeded, "HDR explicit range", got, _oracle(ref, test, "HDR", params))


def test_batched_flip_is_per_frame(seeded):
    ref, test = seeded.pair((2, 32, 40, 3), dtype=np.float32)
    means, maps = metrics.flip(ref, test)
    assert means.shape == (2,) and maps.shape == (2, 32, 40)
    for t in range(2):
        _check(seeded, f"frame {t}", (means[t], maps[t]), _oracle(ref[t], test[t], "LDR"))


def test_filters_follow_flip_defaults():
    # 67.02 ppd: a 21-tap spatial filter and a 19-tap feature filter, as FLIP builds them.
    assert metrics.DEFAULT_PPD == pytest.approx(67.0206, abs=1e-4)
    assert spatial_filter_radius(metrics.DEFAULT_PPD) == 10
    st, ft = spatial_taps(metrics.DEFAULT_PPD), feature_taps(metrics.DEFAULT_PPD)
    assert st.shape == (21, 4) and ft.shape == (19, 3)
    np.testing.assert_allclose(st[:, :2].sum(axis=0), 1.0, err_msg="Y, Cx taps sum to 1")
    np.testing.assert_allclose(st[:, 2].sum() ** 2 + st[:, 3].sum() ** 2, 1.0,
                               err_msg="Cz: the two separable 2-D terms sum to 1")
    for col in (1, 2):  # derivative lobes sum to +1 and -1
        w = ft[:, col]
        np.testing.assert_allclose([w[w > 0].sum(), w[w < 0].sum()], [1.0, -1.0])


def test_flip_bad_arguments():
    a = np.zeros((8, 8, 3), np.float32)
    with pytest.raises(ValueError, match="mode"):
        metrics.flip(a, a, "xdr")
    with pytest.raises(ValueError, match="tonemapper"):
        metrics.flip(a, a, "hdr", tonemapper="filmic")
    with pytest.raises(ValueError, match="channels"):
        metrics.flip(np.zeros((8, 8, 4)), np.zeros((8, 8, 4)))
