"""Temporal metrics over a sequence of test frames I_t and reference frames R_t.

``temporal_error``: the flicker the reference does not have, the mean over t >= 1 and pixels of
|(I_t - I_{t-1}) - (R_t - R_{t-1})|.

``warp_error``: the warping error (Lai et al., ECCV 2018) with an exact reprojection: frame t-1
is resampled at the position each pixel of frame t had in t-1, and
    E(X) = mean_t [ sum_p M_t(p) mean_c (X_t(p) - warp(X_{t-1})(p))^2 / sum_p M_t(p) ]
over the valid (on screen, not disoccluded) pixels M_t. It is reported for the test, the
reference, and relative to the reference's own (a renderer that adds no temporal instability
scores 1).

``reproject`` computes those positions exactly from the known camera motion and the window depth
of frame t (``scene.reprojection``, with the metrics' input checks).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import jaxrender.scene.reprojection as reprojection
from jaxrender.metrics._common import (
    Array,
    as_float,
    check_images,
    has_nan,
    precision,
    resolve_dtype,
    spatial_mean,
)
from jaxrender.scene.camera import Camera
from jaxrender.scene.reprojection import DEFAULT_DEPTH_TOLERANCE, Reprojection

__all__ = ["DEFAULT_DEPTH_TOLERANCE", "Reprojection", "WarpError", "bilinear_sample",
           "reproject", "reproject_sequence", "temporal_error", "warp_error"]


class WarpError(NamedTuple):
    relative: Array  # test / reference; 1 when both are 0, +inf when only the reference is 0
    test: Array
    reference: Array


# ---------------------------------------------------------------------------------------------
# temporal_error


@partial(jax.jit, static_argnames=("per_frame",))
def _temporal_error(test: Array, ref: Array, per_frame: bool) -> Array:
    d = (test[..., 1:, :, :, :] - test[..., :-1, :, :, :]) - (
        ref[..., 1:, :, :, :] - ref[..., :-1, :, :, :])
    per = spatial_mean(jnp.abs(d), 3)  # (..., T-1)
    return per if per_frame else jnp.mean(per, axis=-1)


def _check_sequence(name: str, test, ref) -> None:
    check_images(name, test, ref, channels=None, min_ndim=4)
    if np.shape(test)[-4] < 2:
        raise ValueError(f"{name}: need at least 2 frames along axis -4, got {np.shape(test)}")


def temporal_error(test, reference, *, per_frame: bool = False, dtype=jnp.float32) -> Array:
    """Mean |(I_t - I_{t-1}) - (R_t - R_{t-1})| of (T, H, W, C) sequences (T >= 2): a scalar,
    or (T-1,) values for the frame pairs with ``per_frame=True``."""
    _check_sequence("temporal_error", test, reference)
    with precision(dtype):
        dt = resolve_dtype(dtype)
        i = as_float(test, dt, "temporal_error", "test")
        r = as_float(reference, dt, "temporal_error", "reference")
        return _temporal_error(i, r, per_frame)


# ---------------------------------------------------------------------------------------------
# reproject


def reproject(depth, camera: Camera, prev_camera: Camera, width: int, height: int, *,
              prev_depth=None, depth_tolerance: float = DEFAULT_DEPTH_TOLERANCE,
              dtype=jnp.float32) -> Reprojection:
    """``scene.reprojection.reproject`` with the metrics' input checks: NaN depths raise a
    ValueError naming the input."""
    reprojection.check_depths(depth, prev_depth, width, height)
    resolve_dtype(dtype)
    for what, x in (("depth", depth), ("prev_depth", prev_depth)):
        if x is not None and has_nan(x):
            raise ValueError(f"reproject: input '{what}' contains NaN; metrics are undefined "
                             f"for NaN")
    return reprojection.reproject(depth, camera, prev_camera, width, height,
                                  prev_depth=prev_depth, depth_tolerance=depth_tolerance,
                                  dtype=dtype)


def reproject_sequence(depths, cameras: Camera, *, depth_test: bool = True,
                       depth_tolerance: float = DEFAULT_DEPTH_TOLERANCE,
                       dtype=jnp.float32) -> Reprojection:
    """Reprojection of every frame t = 1..T-1 of a sequence into t-1: depths (T, H, W) and
    cameras stacked along a leading T axis. Returns arrays with a leading T-1 axis."""
    t, h, w = np.shape(depths)
    if t < 2:
        raise ValueError(f"reproject_sequence: need at least 2 frames, got {t}")
    depths = np.asarray(depths) if not isinstance(depths, jax.Array) else depths
    cur = jax.tree.map(lambda a: a[1:], cameras)
    prev = jax.tree.map(lambda a: a[:-1], cameras)
    return reproject(depths[1:], cur, prev, w, h,
                     prev_depth=depths[:-1] if depth_test else None,
                     depth_tolerance=depth_tolerance, dtype=dtype)


# ---------------------------------------------------------------------------------------------
# warp_error


def bilinear_sample(image: Array, position: Array) -> Array:
    """Sample (H, W, C) at window positions (..., 2) (pixel centres at +0.5), clamp to edge."""
    h, w = image.shape[0], image.shape[1]
    u = position[..., 0] - 0.5
    v = position[..., 1] - 0.5
    x0f, y0f = jnp.floor(u), jnp.floor(v)
    fx, fy = (u - x0f)[..., None], (v - y0f)[..., None]
    x0 = jnp.clip(x0f.astype(jnp.int32), 0, w - 1)
    y0 = jnp.clip(y0f.astype(jnp.int32), 0, h - 1)
    x1 = jnp.clip(x0f.astype(jnp.int32) + 1, 0, w - 1)
    y1 = jnp.clip(y0f.astype(jnp.int32) + 1, 0, h - 1)
    top = image[y0, x0] * (1.0 - fx) + image[y0, x1] * fx
    bottom = image[y1, x0] * (1.0 - fx) + image[y1, x1] * fx
    return top * (1.0 - fy) + bottom * fy


def _sequence_warp_error(x: Array, position: Array, mask: Array):
    """Per-pair sums for one sequence (T, H, W, C): masked squared error and mask count."""
    with jax.named_scope("warp"):
        warped = jax.vmap(bilinear_sample)(x[:-1], position)  # (T-1, H, W, C)
    err = jnp.mean((x[1:] - warped) ** 2, axis=-1)  # (T-1, H, W)
    num = jnp.sum(jnp.sum(jnp.where(mask, err, 0.0), axis=-1), axis=-1)
    den = jnp.sum(jnp.sum(mask.astype(x.dtype), axis=-1), axis=-1)
    return num, den


def _frame_average(num: Array, den: Array, per_frame: bool) -> Array:
    has = den > 0.0
    per = jnp.where(has, num / jnp.where(has, den, 1.0), 0.0)
    if per_frame:
        return per
    count = jnp.sum(has.astype(per.dtype), axis=-1)
    return jnp.sum(per, axis=-1) / jnp.maximum(count, 1.0)


@partial(jax.jit, static_argnames=("per_frame",))
def _warp_error(test, ref, position, valid, per_frame):
    fn = _sequence_warp_error
    for _ in range(test.ndim - 4):
        fn = jax.vmap(fn)
    e_test = _frame_average(*fn(test, position, valid), per_frame)
    e_ref = _frame_average(*fn(ref, position, valid), per_frame)
    ref_zero = e_ref == 0.0
    relative = jnp.where(
        ref_zero, jnp.where(e_test == 0.0, 1.0, jnp.inf), e_test / jnp.where(ref_zero, 1.0, e_ref))
    return WarpError(relative, e_test, e_ref)


def warp_error(test, reference, motion, valid=None, *, per_frame: bool = False,
               dtype=jnp.float32) -> WarpError:
    """Warping error of (T, H, W, C) test and reference sequences.

    ``motion`` is a ``Reprojection`` (from ``reproject``/``reproject_sequence``) or an array
    (T-1, H, W, 2) of positions in frame t-1 of the pixels of frame t (t = 1..T-1), with
    ``valid`` (T-1, H, W) (default: all valid). Returns WarpError(relative, test, reference),
    scalars or (T-1,) with ``per_frame=True``.
    """
    if isinstance(motion, Reprojection):
        position, valid = motion.position, motion.valid if valid is None else valid
    else:
        position = motion
    _check_sequence("warp_error", test, reference)
    shape = tuple(np.shape(test))
    pairs = shape[:-4] + (shape[-4] - 1,) + shape[-3:-1]
    if tuple(np.shape(position)) != pairs + (2,):
        raise ValueError(f"warp_error: motion must be {pairs + (2,)}, got {np.shape(position)}")
    if valid is None:
        valid = np.ones(pairs, bool)
    if tuple(np.shape(valid)) != pairs:
        raise ValueError(f"warp_error: valid must be {pairs}, got {np.shape(valid)}")
    with precision(dtype):
        dt = resolve_dtype(dtype)
        i = as_float(test, dt, "warp_error", "test")
        r = as_float(reference, dt, "warp_error", "reference")
        p = as_float(position, dt, "warp_error", "motion")
        v = jnp.asarray(valid).astype(bool)
        return _warp_error(i, r, p, v, per_frame)
