"""Edge cases of issue 5: constant, black, identical, HDR above 1, NaN, single-pixel-wide."""

import colour
import flip_evaluator
import jax.numpy as jnp
import numpy as np
import pytest
from skimage.metrics import (
    mean_squared_error,
    peak_signal_noise_ratio,
    structural_similarity,
)

from jaxrender import metrics

TOL = 1e-6  # float64 against the oracles
FLIP_MEAN_TOL = 1e-3
FLIP_MAP_TOL = 1e-4
DELTA_E_TOL = 1e-4


def _flip_oracle(ref, test, mode="LDR"):
    r = np.ascontiguousarray(ref, np.float32).copy()
    t = np.ascontiguousarray(test, np.float32).copy()
    fmap, mean, _ = flip_evaluator.evaluate(r, t, mode, applyMagma=False)
    return float(mean), np.asarray(fmap).reshape(ref.shape[:2])


def _de_oracle(a, b):
    return colour.delta_E(colour.XYZ_to_Lab(colour.sRGB_to_XYZ(a)),
                          colour.XYZ_to_Lab(colour.sRGB_to_XYZ(b)), method="CIE 2000")


def _all_against_oracles(a, b, what, ssim_ok=True):
    np.testing.assert_allclose(float(metrics.mse(a, b, dtype=np.float64)),
                               mean_squared_error(a, b), atol=TOL, err_msg=f"{what}: mse")
    if mean_squared_error(a, b) > 0:
        np.testing.assert_allclose(float(metrics.psnr(a, b, dtype=np.float64)),
                                   peak_signal_noise_ratio(a, b, data_range=1.0), atol=TOL,
                                   err_msg=f"{what}: psnr")
    if ssim_ok:
        ref = structural_similarity(a, b, data_range=1.0, channel_axis=-1,
                                    gaussian_weights=True, sigma=1.5,
                                    use_sample_covariance=False)
        np.testing.assert_allclose(float(metrics.ssim(a, b, dtype=np.float64)), ref,
                                   atol=TOL, err_msg=f"{what}: ssim")
    mean, fmap = metrics.flip(a, b)
    ref_mean, ref_map = _flip_oracle(a, b)
    np.testing.assert_allclose(float(mean), ref_mean, atol=FLIP_MEAN_TOL, err_msg=f"{what}: flip")
    np.testing.assert_allclose(np.asarray(fmap), ref_map, atol=FLIP_MAP_TOL,
                               err_msg=f"{what}: flip map")
    mean, de = metrics.delta_e2000(a, b, dtype=np.float64)
    np.testing.assert_allclose(np.asarray(de), _de_oracle(a, b), atol=DELTA_E_TOL,
                               err_msg=f"{what}: delta E")


def test_constant_images():
    a, b = np.full((16, 16, 3), 0.2), np.full((16, 16, 3), 0.7)
    _all_against_oracles(a, b, "constant")
    assert float(metrics.psnr(a, b, dtype=np.float64)) == pytest.approx(-10 * np.log10(0.25))


def test_black_and_black_vs_white():
    black, white = np.zeros((16, 16, 3)), np.ones((16, 16, 3))
    _all_against_oracles(black, white, "black vs white")
    assert float(metrics.psnr(black, black)) == np.inf
    assert float(metrics.ssim(black, black)) == pytest.approx(1.0, abs=1e-6)
    assert float(metrics.flip(black, black)[0]) == 0.0
    assert float(metrics.delta_e2000(black, black)[0]) == 0.0
    assert float(metrics.flip(black * 10, black * 10, "hdr")[0]) == 0.0  # degenerate exposure


def test_identical_images_are_perfect_not_nan(seeded):
    a, _ = seeded.pair((16, 16, 3))
    results = {
        "mse": metrics.mse(a, a), "psnr": metrics.psnr(a, a), "ssim": metrics.ssim(a, a),
        "flip": metrics.flip(a, a)[0], "delta_e": metrics.delta_e2000(a, a)[0],
        "temporal": metrics.temporal_error(np.stack([a, a]), np.stack([a, a])),
    }
    assert not any(np.isnan(float(v)) for v in results.values()), results
    assert float(results["psnr"]) == np.inf
    assert float(results["ssim"]) == pytest.approx(1.0, abs=1e-6)
    assert float(results["mse"]) == float(results["flip"]) == float(results["delta_e"]) == 0.0


def test_hdr_values_above_one(seeded):
    a, b = seeded.pair((16, 16, 3))
    a, b = 6.0 * a, 6.0 * b
    # LDR metrics see the display-referred image: clamp, then encode.
    disp_a, disp_b = metrics.to_display(a), metrics.to_display(b)
    assert float(jnp.max(disp_a)) <= 1.0
    np.testing.assert_allclose(
        float(metrics.mse(disp_a, disp_b)),
        float(metrics.mse(metrics.to_display(np.clip(a, 0, 1)),
                          metrics.to_display(np.clip(b, 0, 1)))), err_msg="clamp before encode")
    # LDR-FLIP clamps out-of-range inputs as flip-evaluator does...
    np.testing.assert_allclose(float(metrics.flip(a, b)[0]), float(metrics.flip(
        np.clip(a, 0, 1), np.clip(b, 0, 1))[0]), atol=1e-7, err_msg="LDR-FLIP clamps")
    # ...and HDR-FLIP uses the range, against flip-evaluator.
    mean, fmap = metrics.flip(a, b, "hdr")
    ref_mean, ref_map = _flip_oracle(a, b, "HDR")
    np.testing.assert_allclose(float(mean), ref_mean, atol=FLIP_MEAN_TOL,
                               err_msg=seeded.msg("hdr flip"))
    np.testing.assert_allclose(np.asarray(fmap), ref_map, atol=FLIP_MAP_TOL,
                               err_msg=seeded.msg("hdr flip map"))


NAN_CALLS = {
    "mse": lambda a, b: metrics.mse(a, b),
    "rmse": lambda a, b: metrics.rmse(a, b),
    "psnr": lambda a, b: metrics.psnr(a, b),
    "ssim": lambda a, b: metrics.ssim(a, b),
    "flip": lambda a, b: metrics.flip(a, b),
    "flip_hdr": lambda a, b: metrics.flip(a, b, "hdr"),
    "delta_e2000": lambda a, b: metrics.delta_e2000(a, b),
    "temporal_error": lambda a, b: metrics.temporal_error(np.stack([a, a]), np.stack([b, b])),
    "image_metrics": lambda a, b: metrics.image_metrics(a, b),
}


@pytest.mark.parametrize("name", sorted(NAN_CALLS))
@pytest.mark.parametrize("as_jax", [False, True])
def test_nan_input_raises(name, as_jax):
    a = np.full((12, 12, 3), 0.5)
    b = a.copy()
    b[3, 4, 1] = np.nan
    if as_jax:
        a, b = jnp.asarray(a), jnp.asarray(b)
    with pytest.raises(ValueError, match="NaN"):
        NAN_CALLS[name](a, b)
    with pytest.raises(ValueError, match="NaN"):
        NAN_CALLS[name](b, a)


def test_nan_in_warp_inputs_raises():
    x = np.zeros((2, 4, 4, 3))
    pos = np.zeros((1, 4, 4, 2))
    pos[0, 0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        metrics.warp_error(x, x, pos)
    depth = np.full((4, 4), np.nan)
    from jaxrender.scene.camera import look_at

    cam = look_at((0, 0, 0), (0, 0, -1))
    with pytest.raises(ValueError, match="NaN"):
        metrics.reproject(depth, cam, cam, 4, 4)


@pytest.mark.parametrize("shape", [(20, 1, 3), (1, 20, 3)])
def test_single_pixel_wide_images(seeded, shape):
    a, b = seeded.pair(shape)
    _all_against_oracles(a, b, f"shape {shape}", ssim_ok=False)
    with pytest.raises(ValueError, match="window"):
        metrics.ssim(a, b)
    seq = metrics.temporal_error(np.stack([a, b]), np.stack([b, a]), dtype=np.float64)
    np.testing.assert_allclose(float(seq), 2 * np.abs(b - a).mean(), atol=TOL)


def test_many_frames_run_in_chunks(seeded):
    """More frames than one chunk (lax.map over chunks) gives the same values per frame."""
    a, b = seeded.pair((9, 16, 16, 3))
    batched = np.asarray(metrics.ssim(a, b, dtype=np.float64))
    single = [float(metrics.ssim(a[t], b[t], dtype=np.float64)) for t in range(9)]
    np.testing.assert_allclose(batched, single, atol=1e-12, err_msg=seeded.msg("ssim chunks"))
    means, maps = metrics.flip(a[:5], b[:5])
    np.testing.assert_allclose(np.asarray(means)[4], float(metrics.flip(a[4], b[4])[0]),
                               atol=1e-6, err_msg=seeded.msg("flip chunks"))
