"""All image metrics of a frame against its reference in one call, display handled once."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.metrics._common import as_float, precision, resolve_dtype
from jaxrender.metrics.color import delta_e2000
from jaxrender.metrics.display import to_display
from jaxrender.metrics.error import mse, psnr, rmse
from jaxrender.metrics.flip import flip
from jaxrender.metrics.ssim import ssim

IMAGE_METRICS = ("mse", "rmse", "psnr", "ssim", "flip", "delta_e2000")


def image_metrics(test, reference, *, names=IMAGE_METRICS, linear: bool = True,
                  exposure: float = 0.0, dtype=jnp.float32) -> dict:
    """{name: value per image} for LDR metrics. Linear inputs (pipeline output) go through
    ``to_display`` (exposure, clamp, sRGB encode) once; pass ``linear=False`` for images that
    are already display-referred."""
    unknown = set(names) - set(IMAGE_METRICS)
    if unknown:
        raise ValueError(f"image_metrics: unknown metrics {sorted(unknown)}; "
                         f"known: {IMAGE_METRICS}")
    if linear:
        with precision(dtype):
            dt = resolve_dtype(dtype)
            test = to_display(as_float(test, dt, "image_metrics", "test"), "ldr", exposure)
            reference = to_display(as_float(reference, dt, "image_metrics", "reference"),
                                   "ldr", exposure)
    fns = {
        "mse": lambda: mse(test, reference, dtype=dtype),
        "rmse": lambda: rmse(test, reference, dtype=dtype),
        "psnr": lambda: psnr(test, reference, dtype=dtype),
        "ssim": lambda: ssim(test, reference, dtype=dtype),
        "flip": lambda: flip(reference, test, dtype=dtype)[0],
        "delta_e2000": lambda: delta_e2000(test, reference, dtype=dtype)[0],
    }
    return {name: fns[name]() for name in names}
