"""Image-quality and temporal metrics, equal to the reference libraries, jit-compiled and batched.

Images are (H, W, 3) or (T, H, W, 3); each metric returns one value per image (and a per-pixel
map where one makes sense). float32 by default, ``dtype=jnp.float64`` on request.
"""

from collections.abc import Callable
from dataclasses import dataclass

from jaxrender.metrics._common import correlate_impl, set_correlate_impl
from jaxrender.metrics.color import ciede2000, delta_e2000, srgb_to_lab
from jaxrender.metrics.display import srgb_decode, srgb_encode, to_display
from jaxrender.metrics.error import mse, psnr, rmse
from jaxrender.metrics.flip import DEFAULT_PPD, exposure_range, flip
from jaxrender.metrics.ssim import ssim
from jaxrender.metrics.suite import IMAGE_METRICS, image_metrics
from jaxrender.metrics.temporal import (
    Reprojection,
    WarpError,
    bilinear_sample,
    reproject,
    reproject_sequence,
    temporal_error,
    warp_error,
)



@dataclass(frozen=True)
class Metric:
    """A metric a study may ask for by ``name``, the column its value gets in the results.
    ``fn(test, reference)`` takes display-referred images, (H, W, 3), or (T, H, W, 3) for a
    ``sequence`` metric, and returns a value or (value, per-pixel map); the map of the
    ``error_map`` metric is the one the figures show."""

    name: str
    fn: Callable
    sequence: bool = False
    error_map: bool = False


def _flip(test, reference):
    return flip(reference, test)


METRICS: dict[str, Metric] = {m.name: m for m in (
    Metric("rmse", rmse),
    Metric("psnr", psnr),
    Metric("mssim", ssim),
    Metric("flip", _flip, error_map=True),
    Metric("delta_e", delta_e2000),
    Metric("temporal_error", temporal_error, sequence=True),
)}


__all__ = [
    "DEFAULT_PPD",
    "IMAGE_METRICS",
    "METRICS",
    "Metric",
    "Reprojection",
    "WarpError",
    "bilinear_sample",
    "ciede2000",
    "correlate_impl",
    "delta_e2000",
    "exposure_range",
    "flip",
    "image_metrics",
    "mse",
    "psnr",
    "reproject",
    "reproject_sequence",
    "rmse",
    "set_correlate_impl",
    "srgb_decode",
    "srgb_encode",
    "srgb_to_lab",
    "ssim",
    "temporal_error",
    "to_display",
    "warp_error",
]
