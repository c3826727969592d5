"""Image-quality and temporal metrics, equal to the reference libraries, jit-compiled and batched.

Images are (H, W, 3) or (T, H, W, 3); each metric returns one value per image (and a per-pixel
map where one makes sense). float32 by default, ``dtype=jnp.float64`` on request.
"""

from jaxrender.metrics._common import correlate_impl, set_correlate_impl
from jaxrender.metrics.color import ciede2000, delta_e2000, srgb_to_lab
from jaxrender.metrics.display import srgb_decode, srgb_encode, to_display
from jaxrender.metrics.error import mse, psnr, rmse
from jaxrender.metrics.flip import DEFAULT_PPD, exposure_range, flip
from jaxrender.metrics.registry import DEFAULT_METRICS, METRICS, Metric
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

__all__ = [
    "DEFAULT_PPD",
    "DEFAULT_METRICS",
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
