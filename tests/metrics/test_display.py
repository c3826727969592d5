import colour
import numpy as np
import pytest

from jaxrender import metrics

ENCODE_TOL = 1e-6  # float32 transfer function vs colour-science's float64 one


def test_srgb_encode_decode_match_colour(seeded):
    x = np.concatenate([seeded.rng.random(1000), [0.0, 0.0031308, 0.04045, 1.0]])
    enc = np.asarray(metrics.srgb_encode(x.astype(np.float32)))
    np.testing.assert_allclose(enc, colour.models.eotf_inverse_sRGB(x), atol=ENCODE_TOL,
                               err_msg=seeded.msg("sRGB encode"))
    dec = np.asarray(metrics.srgb_decode(x.astype(np.float32)))
    np.testing.assert_allclose(dec, colour.models.eotf_sRGB(x), atol=ENCODE_TOL,
                               err_msg=seeded.msg("sRGB decode"))
    np.testing.assert_allclose(np.asarray(metrics.srgb_decode(metrics.srgb_encode(x))), x,
                               atol=ENCODE_TOL, err_msg=seeded.msg("round trip"))


def test_to_display_clamps_then_encodes():
    linear = np.array([[[-1.0, 0.5, 4.0]]], np.float32)  # below 0, mid, HDR above 1
    ldr = np.asarray(metrics.to_display(linear))
    np.testing.assert_allclose(ldr, [[[0.0, colour.models.eotf_inverse_sRGB(0.5), 1.0]]],
                               atol=ENCODE_TOL)
    hdr = np.asarray(metrics.to_display(linear, "hdr"))
    np.testing.assert_allclose(hdr, [[[0.0, 0.5, 4.0]]])
    # one stop down brings 4.0 to 2.0, still clamped in LDR
    np.testing.assert_allclose(np.asarray(metrics.to_display(linear, "hdr", exposure=-1.0)),
                               [[[0.0, 0.25, 2.0]]])
    with pytest.raises(ValueError, match="mode"):
        metrics.to_display(linear, "pq")


def test_image_metrics_applies_display_once(seeded):
    a, b = seeded.pair((16, 16, 3))
    lin_a, lin_b = 2.0 * a, 2.0 * b  # linear HDR frames
    got = metrics.image_metrics(lin_b, lin_a)
    disp_a, disp_b = metrics.to_display(lin_a), metrics.to_display(lin_b)
    np.testing.assert_allclose(float(got["rmse"]), float(metrics.rmse(disp_b, disp_a)),
                               err_msg=seeded.msg("rmse"))
    np.testing.assert_allclose(float(got["mssim"]), float(metrics.ssim(disp_b, disp_a)),
                               err_msg=seeded.msg("mssim"))
    np.testing.assert_allclose(float(got["flip"]), float(metrics.flip(disp_a, disp_b)[0]),
                               err_msg=seeded.msg("flip: reference first"))
    assert set(got) == set(metrics.IMAGE_METRICS)
    with pytest.raises(ValueError, match="unknown"):
        metrics.image_metrics(a, b, names=("lpips",))


MAP_TOL = 1e-6  # float32 display images


def test_image_metrics_error_map(seeded):
    a, b = seeded.pair((12, 20, 3))
    values, flip_map = metrics.image_metrics(b, a, names=("rmse", "flip"), error_map=True)
    disp_a, disp_b = np.asarray(metrics.to_display(a)), np.asarray(metrics.to_display(b))
    np.testing.assert_allclose(np.asarray(flip_map), np.asarray(metrics.flip(disp_a, disp_b)[1]),
                               atol=MAP_TOL, err_msg=seeded.msg("the flip metric's map"))
    assert set(values) == {"rmse", "flip"}
    _, mean_map = metrics.image_metrics(b, a, names=("rmse",), error_map=True)
    np.testing.assert_allclose(np.asarray(mean_map), np.abs(disp_b - disp_a).mean(-1),
                               atol=MAP_TOL, err_msg=seeded.msg("mean absolute display error"))
