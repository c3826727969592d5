import importlib

import jax
import numpy as np
import pytest
from skimage.metrics import structural_similarity

from jaxrender import metrics

TOL_F64 = 1e-6  # issue 5: agreement with scikit-image in float64
TOL_F32 = 1e-4  # ... and in float32

WANG = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False)  # Wang et al. 2004
SKIMAGE_DEFAULT = {}  # 7x7 uniform window, sample covariance
SETTINGS = [("gaussian", WANG), ("uniform7", SKIMAGE_DEFAULT)]


def _skimage(a, b, kwargs, data_range=1.0, full=False):
    return structural_similarity(a, b, data_range=data_range, channel_axis=-1, full=full,
                                 **kwargs)


@pytest.mark.parametrize("window,kwargs", SETTINGS)
@pytest.mark.parametrize("dtype,tol", [(np.float64, TOL_F64), (np.float32, TOL_F32)])
def test_ssim_matches_skimage(seeded, window, kwargs, dtype, tol):
    a, b = seeded.pair()
    ref_mean, ref_map = _skimage(a, b, kwargs, full=True)
    got_mean, got_map = metrics.ssim(a, b, window=window, full=True, dtype=dtype)
    assert got_mean.dtype == dtype and got_map.shape == a.shape
    np.testing.assert_allclose(float(got_mean), ref_mean, rtol=0, atol=tol,
                               err_msg=seeded.msg(f"mssim {window}"))
    np.testing.assert_allclose(np.asarray(got_map), ref_map, rtol=0, atol=tol,
                               err_msg=seeded.msg(f"ssim map {window}"))
    # without the map: the cropped-border mean alone
    np.testing.assert_allclose(float(metrics.ssim(a, b, window=window, dtype=dtype)), ref_mean,
                               rtol=0, atol=tol, err_msg=seeded.msg(f"mssim no map {window}"))


def test_ssim_batched_and_data_range(seeded):
    a, b = seeded.pair((3, 24, 32, 3))
    a, b = 3.0 * a, 3.0 * b  # HDR values above 1 with their data range
    got = np.asarray(metrics.ssim(a, b, data_range=3.0, dtype=np.float64))
    assert got.shape == (3,)
    ref = [_skimage(a[t], b[t], WANG, data_range=3.0) for t in range(3)]
    np.testing.assert_allclose(got, ref, atol=TOL_F64, err_msg=seeded.msg("batched ssim"))


def test_ssim_constant_and_identical(seeded):
    a, _ = seeded.pair()
    assert float(metrics.ssim(a, a, dtype=np.float64)) == pytest.approx(1.0, abs=1e-12)
    c1, c2 = np.full((20, 20, 3), 0.25), np.full((20, 20, 3), 0.75)
    for window, kwargs in SETTINGS:
        np.testing.assert_allclose(
            float(metrics.ssim(c1, c2, window=window, dtype=np.float64)),
            _skimage(c1, c2, kwargs), atol=TOL_F64, err_msg=f"constant images, {window}")
    black = np.zeros((20, 20, 3))
    assert float(metrics.ssim(black, black)) == pytest.approx(1.0, abs=1e-6)


def test_ssim_too_small_raises():
    thin = np.zeros((30, 1, 3))
    with pytest.raises(ValueError, match="window"):
        metrics.ssim(thin, thin)
    with pytest.raises(ValueError):  # scikit-image refuses it too
        _skimage(thin, thin, WANG)
    with pytest.raises(ValueError, match="window"):  # 8x8 is smaller than the 11x11 Gaussian
        metrics.ssim(np.zeros((8, 8, 3)), np.zeros((8, 8, 3)))
    with pytest.raises(ValueError, match="window must be one of"):
        metrics.ssim(np.zeros((16, 16, 3)), np.zeros((16, 16, 3)), window="box")


def test_ssim_compiles_once_per_shape(seeded):
    a, b = seeded.pair()
    metrics.ssim(a, b)
    ssim_module = importlib.import_module("jaxrender.metrics.ssim")
    before = ssim_module._ssim._cache_size()
    c, d = seeded.pair()
    metrics.ssim(c, d)
    metrics.ssim(jax.numpy.asarray(c, np.float32), d)
    assert ssim_module._ssim._cache_size() == before, "new data of the same shape recompiled"
