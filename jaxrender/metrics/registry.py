"""The metrics by the names a study asks for them and its results' columns carry: the one
vocabulary of ``jaxrender.metrics`` (``image_metrics`` takes the same names)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from jaxrender.metrics.color import delta_e2000
from jaxrender.metrics.error import psnr, rmse
from jaxrender.metrics.flip import flip
from jaxrender.metrics.ssim import ssim
from jaxrender.metrics.temporal import temporal_error, warp_error


@dataclass(frozen=True)
class Metric:
    """A metric a study may ask for by ``name``, the column its value gets in the results.
    ``fn(test, reference, dtype=...)`` takes display-referred images, (H, W, 3), or (T, H, W, 3) for a
    ``sequence`` metric, and returns a value or (value, per-pixel map); the map of the
    ``error_map`` metric is the one the figures show. A ``motion`` metric also takes the
    sequence's motion field, ``fn(test, reference, motion)`` (a Reprojection of frames 1..T-1
    into their previous frames, ``pipelines.motion_field``). ``default``: computed when a study
    names no metrics (the motion field is a render pass of its own)."""

    name: str
    fn: Callable
    sequence: bool = False
    error_map: bool = False
    motion: bool = False
    default: bool = True


def _flip(test, reference, **kw):
    return flip(reference, test, **kw)


def _mean_flip(test, reference, **kw):
    """The mean over frames of each frame's FLIP."""
    return float(np.mean(np.asarray(flip(reference, test, **kw)[0], np.float64)))


def _warp_error(test, reference, motion, **kw):
    """The motion-compensated warping error relative to the reference's own."""
    return warp_error(test, reference, motion, **kw).relative


def _warp_error_test(test, reference, motion, **kw):
    """The test sequence's own warping error, not divided by the reference's: finite on a
    still scene, where the reference does not change and the ratio is +inf for any flicker."""
    return warp_error(test, reference, motion, **kw).test


METRICS: dict[str, Metric] = {m.name: m for m in (
    Metric("rmse", rmse),
    Metric("psnr", psnr),
    Metric("mssim", ssim),
    Metric("flip", _flip, error_map=True),
    Metric("delta_e", delta_e2000),
    Metric("temporal_error", temporal_error, sequence=True),
    Metric("warp_error", _warp_error, sequence=True, motion=True, default=False),
    Metric("warp_error_test", _warp_error_test, sequence=True, motion=True, default=False),
    Metric("mean_flip", _mean_flip, sequence=True, default=False),
)}
DEFAULT_METRICS = tuple(n for n, m in METRICS.items() if m.default)
