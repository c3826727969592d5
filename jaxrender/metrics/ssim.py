"""Structural similarity (Wang et al. 2004), equal to ``skimage.metrics.structural_similarity``.

Default (``window="gaussian"``): Gaussian window sigma 1.5 truncated at 3.5 sigma (11 taps),
population covariance, K1 = 0.01, K2 = 0.03: the paper's MSSIM. ``window="uniform7"``:
scikit-image's defaults, a 7x7 box with sample covariance (N / (N - 1)). SSIM is computed per channel and then
averaged; the mean skips a border of (taps - 1) / 2 pixels, as scikit-image crops it. The map
(``full=True``) is full size with scikit-image's border handling (half-sample symmetric reflection,
``scipy.ndimage`` mode "reflect").
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.metrics._common import (
    Array,
    correlate_valid,
    map_frames,
    pad_axis,
    precision,
    prepare,
    spatial_mean,
)

K1 = 0.01
K2 = 0.03
GAUSSIAN_SIGMA = 1.5
GAUSSIAN_TRUNCATE = 3.5  # scikit-image's truncate: radius = int(3.5 * 1.5 + 0.5) = 5
UNIFORM_SIZE = 7
WINDOWS = ("gaussian", "uniform7")
FRAMES_PER_CHUNK = 8


def window_taps(window: str) -> tuple[np.ndarray, bool]:
    """1-D taps (float64) of the separable window and whether covariance is the sample one."""
    if window == "gaussian":
        radius = int(GAUSSIAN_TRUNCATE * GAUSSIAN_SIGMA + 0.5)
        x = np.arange(-radius, radius + 1, dtype=np.float64)
        w = np.exp(-0.5 * x * x / (GAUSSIAN_SIGMA * GAUSSIAN_SIGMA))
        return w / w.sum(), False
    if window == "uniform7":
        return np.full(UNIFORM_SIZE, 1.0 / UNIFORM_SIZE), True
    raise ValueError(f"ssim: window must be one of {WINDOWS}, got {window!r}")


def _ssim_map(a: Array, b: Array, data_range: Array, window: str, full: bool) -> Array:
    """SSIM map of (..., H, W, C) images: valid region, or full size with reflected borders."""
    taps_np, sample_cov = window_taps(window)
    n = taps_np.shape[0]
    radius = (n - 1) // 2
    taps = jnp.asarray(taps_np, a.dtype)
    # Filter the five moments in one pass: (5, ..., H, W, C).
    stack = jnp.stack([a, b, a * a, b * b, a * b])
    for axis in (-3, -2):
        if full:
            stack = pad_axis(stack, radius, axis, "symmetric")
        stack = correlate_valid(stack, taps, axis)
    ux, uy, uxx, uyy, uxy = stack[0], stack[1], stack[2], stack[3], stack[4]
    cov_norm = n * n / (n * n - 1.0) if sample_cov else 1.0
    vx = cov_norm * (uxx - ux * ux)
    vy = cov_norm * (uyy - uy * uy)
    vxy = cov_norm * (uxy - ux * uy)
    c1 = (K1 * data_range) * (K1 * data_range)
    c2 = (K2 * data_range) * (K2 * data_range)
    num = (2.0 * ux * uy + c1) * (2.0 * vxy + c2)
    den = (ux * ux + uy * uy + c1) * (vx + vy + c2)
    return num / den


@partial(jax.jit, static_argnames=("window", "full"))
def _ssim(a: Array, b: Array, data_range: Array, window: str, full: bool):
    radius = (window_taps(window)[0].shape[0] - 1) // 2

    def per_chunk(x, y):
        with jax.named_scope(f"ssim_{window}"):
            s = _ssim_map(x, y, data_range, window, full)
        inner = s[..., radius:-radius, radius:-radius, :] if full else s
        mean = spatial_mean(inner, 3)  # equal-size channels: mean of channel means
        return (mean, s) if full else (mean, None)

    return map_frames(per_chunk, (a, b), FRAMES_PER_CHUNK)


def ssim(a, b, data_range: float = 1.0, *, window: str = "gaussian", full: bool = False,
         dtype=jnp.float32):
    """Mean SSIM per image (scalar, or (T,) for a batch); with ``full=True`` also the map
    (..., H, W, C). Raises ValueError if an image is smaller than the window."""
    taps, _ = window_taps(window)
    n = taps.shape[0]
    if not data_range > 0.0:
        raise ValueError(f"ssim: data_range must be positive, got {data_range}")
    shape = np.shape(a)
    if len(shape) >= 3 and (shape[-3] < n or shape[-2] < n):
        raise ValueError(
            f"ssim: images of {shape[-3]}x{shape[-2]} pixels are smaller than the "
            f"{n}x{n} window ({window!r}); SSIM is undefined there"
        )
    with precision(dtype):
        a, b = prepare("ssim", a, b, dtype, channels=None)
        mean, smap = _ssim(a, b, jnp.asarray(data_range, a.dtype), window, full)
    return (mean, smap) if full else mean
