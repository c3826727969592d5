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
                  exposure: float = 0.0, dtype=jnp.float32, error_map: bool = False):
    """{name: value per image} for LDR metrics. Linear inputs (pipeline output) go through
    ``to_display`` (exposure, clamp, sRGB encode) once; pass ``linear=False`` for images that
    are already display-referred.

    With ``error_map`` also the per-pixel error the figures show, as ``(values, map)``: the
    map of the registry's ``error_map`` metric when it is among ``names`` and returns one of
    the image's size, else the mean absolute display difference over the channels."""
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
    out, err = {}, None
    for name in names:
        fn = mse if name == "mse" else METRICS[name].fn
        value = fn(test, reference, dtype=dtype)
        out[name] = value[0] if isinstance(value, tuple) else value
        if name != "mse" and METRICS[name].error_map and isinstance(value, tuple):
            err = value[1]
    if not error_map:
        return out
    *shape, channels = jnp.shape(test)
    if err is None or jnp.shape(err) != tuple(shape):
        err = jnp.sum(jnp.abs(jnp.asarray(test) - jnp.asarray(reference)), axis=-1) / channels
    return out, err
