"""Input checks, precision and reductions shared by every metric.

Every public metric runs the same preamble on the host: shapes are checked, NaN inputs raise a
ValueError naming the metric, and the arrays are cast to the requested float dtype. Float64 is
only ever switched on inside ``precision(dtype)``, never globally.
"""

from __future__ import annotations

import contextlib

import jax
import jax.numpy as jnp
import numpy as np

Array = jax.Array

FLOAT_DTYPES = {np.dtype(np.float32): jnp.float32, np.dtype(np.float64): jnp.float64}


def resolve_dtype(dtype) -> np.dtype:
    dt = np.dtype(dtype)
    if dt not in FLOAT_DTYPES:
        raise ValueError(f"dtype must be float32 or float64, got {dt}")
    return dt


def precision(dtype) -> contextlib.AbstractContextManager:
    """A context that enables 64-bit JAX for the duration of a float64 request only."""
    if resolve_dtype(dtype) == np.float64:
        return jax.enable_x64(True)
    return contextlib.nullcontext()


@jax.jit
def _any_nan(x: Array) -> Array:
    return jnp.any(jnp.isnan(x))


def has_nan(x) -> bool:
    """True where ``x`` holds a NaN. NumPy inputs are checked on the host; JAX arrays on their
    device with a single boolean brought back (no copy of the images). Tracers cannot be
    checked and are let through."""
    if isinstance(x, jax.core.Tracer):
        return False
    if isinstance(x, jax.Array):
        if not jnp.issubdtype(x.dtype, jnp.floating):
            return False
        return bool(_any_nan(x))
    arr = np.asarray(x)
    return bool(np.issubdtype(arr.dtype, np.floating) and np.isnan(arr).any())


def as_float(x, dtype: np.dtype, name: str, what: str) -> Array:
    """Check ``x`` for NaN and cast it to ``dtype`` (call inside ``precision(dtype)``)."""
    if has_nan(x):
        raise ValueError(f"{name}: input '{what}' contains NaN; metrics are undefined for NaN")
    if isinstance(x, jax.Array):
        return x.astype(dtype)
    return jnp.asarray(np.asarray(x, dtype=dtype))


def check_images(name: str, a, b, *, channels: int | None = 3, min_ndim: int = 3) -> None:
    """Images are (..., H, W, C) with identical shapes; C == channels where one is required."""
    sa, sb = tuple(np.shape(a)), tuple(np.shape(b))
    if sa != sb:
        raise ValueError(f"{name}: shapes differ: {sa} vs {sb}")
    if len(sa) < min_ndim:
        raise ValueError(f"{name}: expected (H, W, C) or (T, H, W, C) images, got shape {sa}")
    if channels is not None and sa[-1] != channels:
        raise ValueError(f"{name}: expected {channels} channels in the last axis, got {sa}")
    if 0 in sa:
        raise ValueError(f"{name}: empty image of shape {sa}")


def prepare(name: str, a, b, dtype, *, channels: int | None = 3) -> tuple[Array, Array]:
    """The common preamble: shape checks, NaN checks, cast. Call inside ``precision(dtype)``."""
    check_images(name, a, b, channels=channels)
    dt = resolve_dtype(dtype)
    return as_float(a, dt, name, "a"), as_float(b, dt, name, "b")


def spatial_mean(x: Array, naxes: int) -> Array:
    """Mean over the last ``naxes`` axes, one axis at a time: each partial sum stays short, so
    float32 accumulation over a 1080p frame keeps close to float64 accuracy."""
    for _ in range(naxes):
        x = jnp.mean(x, axis=-1)
    return x


def broadcast_taps(taps: Array, ndim: int) -> Array:
    """(n,) or (n, C) tap table reshaped so that ``taps[k]`` broadcasts against an array of rank
    ``ndim`` whose last axis holds the C channels (explicit shapes, as strict rank promotion
    requires); the filtered axis is the slicing's business, not the taps'."""
    n = taps.shape[0]
    if taps.ndim == 1:
        return taps.reshape((n,) + (1,) * ndim)
    shape = [1] * ndim
    shape[-1] = taps.shape[1]
    return taps.reshape((n,) + tuple(shape))


# How the separable filters run: "slices" (sum of shifted slices, each pass materialised) is
# the default; "conv" (one depthwise XLA convolution per pass) compiles faster but XLA:CPU runs
# it ~10x slower. Read at trace time; benchmarks/bench_metrics.py --impl compares the two.
CORRELATE_IMPL = "slices"


def correlate_impl() -> str:
    """How the separable filters (SSIM, FLIP) run: "slices" or "conv"."""
    return CORRELATE_IMPL


def set_correlate_impl(impl: str) -> None:
    """Choose "slices" or "conv" (see CORRELATE_IMPL); set it before a metric is traced."""
    global CORRELATE_IMPL
    if impl not in ("slices", "conv"):
        raise ValueError(f"correlate impl: expected 'slices' or 'conv', got {impl!r}")
    CORRELATE_IMPL = impl


def correlate_valid(x: Array, taps: Array, axis: int) -> Array:
    """1-D correlation along ``axis`` (-3 = H or -2 = W of a (..., H, W, C) array) over the
    valid region: out[i] = sum_k taps[k] x[i + k]. ``taps`` is (n,) (same for every channel) or
    (n, C) (one filter per channel). Elementwise in the working precision on every backend
    (never TF32)."""
    if axis % x.ndim not in (x.ndim - 3, x.ndim - 2):
        raise ValueError(f"correlate_valid: axis must be H (-3) or W (-2), got {axis}")
    if CORRELATE_IMPL == "conv":
        return _correlate_conv(x, taps, axis)
    return _correlate_slices(x, taps, axis)


def _correlate_slices(x: Array, taps: Array, axis: int) -> Array:
    n = taps.shape[0]
    axis = axis % x.ndim
    length = x.shape[axis] - n + 1
    t = broadcast_taps(taps.astype(x.dtype), x.ndim)
    acc = t[0] * jax.lax.slice_in_dim(x, 0, length, axis=axis)
    for k in range(1, n):
        acc = acc + t[k] * jax.lax.slice_in_dim(x, k, k + length, axis=axis)
    # Materialise each pass: otherwise XLA fuses the first pass into every tap of the second
    # (n^2 work per pixel, and slow compiles).
    return jax.lax.optimization_barrier(acc)


def _correlate_conv(x: Array, taps: Array, axis: int) -> Array:
    n, c = taps.shape[0], x.shape[-1]
    taps = taps.astype(x.dtype)
    if taps.ndim == 1:
        taps = jnp.broadcast_to(taps[:, None], (n, c))
    lead = x.shape[:-3]
    along_h = axis % x.ndim == x.ndim - 3
    kernel = taps.reshape((n, 1, 1, c) if along_h else (1, n, 1, c))  # HWIO, depthwise
    out = jax.lax.conv_general_dilated(
        x.reshape((-1,) + x.shape[-3:]), kernel, window_strides=(1, 1), padding="VALID",
        dimension_numbers=("NHWC", "HWIO", "NHWC"), feature_group_count=c,
        precision=jax.lax.Precision.HIGHEST)
    return out.reshape(lead + out.shape[1:])


def pad_axis(x: Array, radius: int, axis: int, mode: str) -> Array:
    axis = axis % x.ndim
    widths = [(0, 0)] * x.ndim
    widths[axis] = (radius, radius)
    return jnp.pad(x, widths, mode=mode)


def map_frames(fn, arrays: tuple[Array, ...], batch_size: int):
    """Apply ``fn`` (which accepts a leading frame axis) to frames of (..., H, W, C) arrays,
    ``batch_size`` frames at a time so that 60 1080p frames never hold every intermediate at
    once. Leading axes are flattened and restored on the outputs."""
    lead = arrays[0].shape[:-3]
    if not lead:
        return fn(*arrays)
    n = int(np.prod(lead))
    flat = tuple(a.reshape((n,) + a.shape[-3:]) for a in arrays)
    if n <= batch_size:
        out = fn(*flat)
    else:
        out = jax.lax.map(lambda xs: fn(*xs), flat, batch_size=batch_size)
    return jax.tree.map(lambda o: o.reshape(lead + o.shape[1:]), out)
