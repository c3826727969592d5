"""Pixel error: MSE, RMSE and PSNR, one value per image.

Images are (H, W, C) or (..., H, W, C); the mean runs over H, W and C (as
``skimage.metrics.mean_squared_error`` does), so a batch gives one value per frame.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.metrics._common import Array, precision, prepare, spatial_mean


@jax.jit
def _mse(a: Array, b: Array) -> Array:
    d = a - b
    return spatial_mean(d * d, 3)


@jax.jit
def _rmse(a: Array, b: Array) -> Array:
    return jnp.sqrt(_mse(a, b))


@jax.jit
def _psnr(a: Array, b: Array, data_range: Array) -> Array:
    m = _mse(a, b)
    # Identical images: data_range**2 / 0 = +inf and log10(+inf) = +inf, never NaN.
    return 10.0 * jnp.log10((data_range * data_range) / m)


def mse(a, b, *, dtype=jnp.float32) -> Array:
    """Mean squared error per image: a scalar for (H, W, C), shape (T,) for (T, H, W, C)."""
    with precision(dtype):
        a, b = prepare("mse", a, b, dtype, channels=None)
        return _mse(a, b)


def rmse(a, b, *, dtype=jnp.float32) -> Array:
    """Root mean squared error per image."""
    with precision(dtype):
        a, b = prepare("rmse", a, b, dtype, channels=None)
        return _rmse(a, b)


def psnr(a, b, data_range: float = 1.0, *, dtype=jnp.float32) -> Array:
    """Peak signal-to-noise ratio in dB, ``10 log10(data_range**2 / mse)``; +inf for identical
    images (as scikit-image, but without its divide-by-zero warning)."""
    if not data_range > 0.0:
        raise ValueError(f"psnr: data_range must be positive, got {data_range}")
    with precision(dtype):
        a, b = prepare("psnr", a, b, dtype, channels=None)
        return _psnr(a, b, jnp.asarray(data_range, a.dtype))
