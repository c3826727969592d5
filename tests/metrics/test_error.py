import numpy as np
import pytest
from skimage.metrics import mean_squared_error, peak_signal_noise_ratio

from jaxrender import metrics

TOL_F64 = 1e-6  # issue 5: agreement with scikit-image in float64
TOL_F32 = 1e-4  # ... and in float32
TOL_PSNR_F32 = 1e-4  # dB; PSNR is a log, so its float32 error is relative to the MSE's


@pytest.mark.parametrize("dtype,tol", [(np.float64, TOL_F64), (np.float32, TOL_F32)])
def test_mse_rmse_psnr_match_skimage(seeded, dtype, tol):
    a, b = seeded.pair()
    ref_mse = mean_squared_error(a, b)
    ref_psnr = peak_signal_noise_ratio(a, b, data_range=1.0)
    got_mse = metrics.mse(a, b, dtype=dtype)
    assert got_mse.dtype == dtype
    np.testing.assert_allclose(float(got_mse), ref_mse, rtol=tol, atol=tol * ref_mse,
                               err_msg=seeded.msg("mse"))
    np.testing.assert_allclose(float(metrics.rmse(a, b, dtype=dtype)), np.sqrt(ref_mse),
                               rtol=tol, err_msg=seeded.msg("rmse"))
    np.testing.assert_allclose(float(metrics.psnr(a, b, dtype=dtype)), ref_psnr, rtol=0,
                               atol=tol, err_msg=seeded.msg("psnr"))


def test_psnr_data_range_hdr(seeded):
    a, b = seeded.pair()
    a, b = 4.0 * a, 4.0 * b  # HDR values above 1
    ref = peak_signal_noise_ratio(a, b, data_range=4.0)
    got = float(metrics.psnr(a, b, data_range=4.0, dtype=np.float64))
    np.testing.assert_allclose(got, ref, atol=TOL_F64, err_msg=seeded.msg("psnr hdr"))


def test_batched_one_value_per_frame(seeded):
    a, b = seeded.pair((3, 16, 20, 3))
    got = np.asarray(metrics.psnr(a, b, dtype=np.float64))
    assert got.shape == (3,)
    ref = [peak_signal_noise_ratio(a[t], b[t], data_range=1.0) for t in range(3)]
    np.testing.assert_allclose(got, ref, atol=TOL_F64, err_msg=seeded.msg("batched psnr"))
    assert metrics.mse(a[0], b[0]).shape == ()


def test_identical_gives_inf_not_nan(seeded):
    a, _ = seeded.pair()
    for dtype in (np.float32, np.float64):
        assert float(metrics.mse(a, a, dtype=dtype)) == 0.0
        assert float(metrics.psnr(a, a, dtype=dtype)) == np.inf
    # one identical frame in a batch is +inf, the others finite
    b = a.copy()
    b[0, 0, 0] = 1.0 - b[0, 0, 0]
    got = np.asarray(metrics.psnr(np.stack([a, a]), np.stack([a, b])))
    assert got[0] == np.inf and np.isfinite(got[1]), got


def test_bad_arguments():
    a = np.zeros((4, 4, 3))
    with pytest.raises(ValueError, match="shapes differ"):
        metrics.mse(a, np.zeros((4, 5, 3)))
    with pytest.raises(ValueError, match="data_range"):
        metrics.psnr(a, a, data_range=0.0)
    with pytest.raises(ValueError, match="dtype"):
        metrics.mse(a, a, dtype=np.float16)
