"""All image metrics of a frame against its reference in one call, display handled once."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.metrics._common import as_float, precision, resolve_dtype
from jaxrender.metrics.display import to_display
from jaxrender.metrics.error import mse
from jaxrender.metrics.registry import METRICS

# The registry's per-image metrics, and the MSE beneath RMSE and PSNR.
IMAGE_METRICS = ("mse", *(n for n, m in METRICS.items() if not m.sequence))


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
    out = {}
    for name in names:
        fn = mse if name == "mse" else METRICS[name].fn
        value = fn(test, reference, dtype=dtype)
        out[name] = value[0] if isinstance(value, tuple) else value
    return out
