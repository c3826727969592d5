"""The metrics by the names a study asks for them and its results' columns carry: the one
vocabulary of ``jaxrender.metrics`` (``image_metrics`` takes the same names)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from jaxrender.metrics.color import delta_e2000
from jaxrender.metrics.error import psnr, rmse
from jaxrender.metrics.flip import flip
from jaxrender.metrics.ssim import ssim
from jaxrender.metrics.temporal import temporal_error


@dataclass(frozen=True)
class Metric:
    """A metric a study may ask for by ``name``, the column its value gets in the results.
    ``fn(test, reference, dtype=...)`` takes display-referred images, (H, W, 3), or (T, H, W, 3) for a
    ``sequence`` metric, and returns a value or (value, per-pixel map); the map of the
    ``error_map`` metric is the one the figures show."""

    name: str
    fn: Callable
    sequence: bool = False
    error_map: bool = False


def _flip(test, reference, **kw):
    return flip(reference, test, **kw)


METRICS: dict[str, Metric] = {m.name: m for m in (
    Metric("rmse", rmse),
    Metric("psnr", psnr),
    Metric("mssim", ssim),
    Metric("flip", _flip, error_map=True),
    Metric("delta_e", delta_e2000),
    Metric("temporal_error", temporal_error, sequence=True),
)}
