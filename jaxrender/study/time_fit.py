"""Frame time as a line in shading work: a pipeline's fixed cost and its cost per unit of work,
and the shader cost at which one pipeline overtakes another. Pure NumPy.

``fit_line(work, time_ms)`` is the ordinary least-squares line time = intercept + slope * work,
with work in millions of layer evaluations (``shader_cost.shading_work``): the intercept is
the fixed cost in ms (what the frame costs with a free shader), the slope the ms per million
layer evaluations. Standard errors are the textbook OLS ones (residual variance over n - 2
degrees of freedom); with two points they are NaN.

Linearity check. A series is called linear when the line reproduces every measured time within
``rel_tol`` of that time (or ``abs_tol_ms``, whichever is larger). Why an effect size and not a
significance test: a time series of a study has a handful of points (one per shader cost), so
a lack-of-fit test has one or two degrees of freedom and no power, while the medians of a GPU
are so repeatable that with replicates it would reject every series over a bend far too small
to matter. What matters to the intercept and the crossovers read off the line is whether the
line describes the times within the timing's reproducibility, which is what the check asks;
the largest relative residual is reported beside it.

``crossover(test, baseline)``: with time(c) = a + b * I (1 + c) / 1e6 for a pipeline of
``I`` shade invocations per frame at shader cost c, the cost c* where the two lines meet,
from which ``test`` is the faster one, with a delta-method standard error. It is None (with
the reason) when the lines do not cross at a non-negative cost in that direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MILLION = 1e6
REL_TOL = 0.10  # a measured time may differ from the line by 10% ...
ABS_TOL_MS = 0.05  # ... or by 50 us, whichever is larger (timer and launch jitter)


@dataclass(frozen=True)
class LinearFit:
    """time_ms = intercept_ms + slope_ms * work / 1e6, fitted to ``n`` points."""

    n: int
    intercept_ms: float
    intercept_se: float
    slope_ms: float  # ms per million layer evaluations
    slope_se: float
    covariance: float  # cov(intercept, slope), for errors of quantities of both
    r2: float
    max_rel_residual: float  # largest |time - line| / time over the points
    linear: bool
    note: str  # why the series is not linear ("" when it is)

    def predict(self, work):
        return self.intercept_ms + self.slope_ms * np.asarray(work, np.float64) / MILLION


def fit_line(work, time_ms, *, rel_tol: float = REL_TOL,
             abs_tol_ms: float = ABS_TOL_MS) -> LinearFit:
    """The least-squares line of ``time_ms`` against ``work`` (layer evaluations), with the
    linearity check above. ValueError for fewer than two distinct amounts of work."""
    x = np.asarray(work, np.float64).ravel() / MILLION
    y = np.asarray(time_ms, np.float64).ravel()
    if x.shape != y.shape:
        raise ValueError(f"fit_line: {x.size} amounts of work for {y.size} times")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("fit_line: work and times must be finite")
    n = x.size
    sxx = float(np.sum((x - x.mean()) ** 2)) if n else 0.0
    if n < 2 or sxx <= 0.0:
        raise ValueError("fit_line: needs at least two distinct amounts of work")
    slope = float(np.sum((x - x.mean()) * (y - y.mean())) / sxx)
    intercept = float(y.mean() - slope * x.mean())
    resid = y - (intercept + slope * x)
    sse, sst = float(np.sum(resid ** 2)), float(np.sum((y - y.mean()) ** 2))
    s2 = sse / (n - 2) if n > 2 else math.nan
    var_slope = s2 / sxx
    var_intercept = s2 * (1.0 / n + x.mean() ** 2 / sxx)
    r2 = 1.0 - sse / sst if sst > 0 else (1.0 if sse == 0 else math.nan)
    allowed = np.maximum(rel_tol * np.abs(y), abs_tol_ms)
    bad = np.abs(resid) > allowed
    rel = float(np.max(np.abs(resid) / np.maximum(np.abs(y), 1e-12)))
    note = ""
    if bad.any():
        i = int(np.argmax(np.abs(resid) / allowed))
        note = (f"{int(bad.sum())} of {n} times off the line by more than "
                f"{rel_tol:.0%} (worst: {y[i]:.3g} ms measured, {y[i] - resid[i]:.3g} ms fitted)")
    return LinearFit(n, intercept, math.sqrt(var_intercept), slope, math.sqrt(var_slope),
                     -x.mean() * s2 / sxx, r2, rel, not bad.any(), note)


def no_fit(n: int, note: str) -> LinearFit:
    """The 'fit' of a series no line can be fitted to (its work does not vary): NaNs, not
    linear, ``note`` saying why."""
    nan = math.nan
    return LinearFit(n, nan, nan, nan, nan, nan, nan, nan, False, note)


@dataclass(frozen=True)
class Crossover:
    """The shader cost from which ``test`` is faster than the baseline (None: never)."""

    cost: float | None
    cost_se: float
    note: str


def _per_cost(fit: LinearFit, invocations: float) -> tuple[float, float]:
    """(ms per layer, i.e. per unit of 1 + shader cost, and its variance): slope x
    invocations."""
    k = invocations / MILLION
    return fit.slope_ms * k, (fit.slope_se * k) ** 2


def crossover(test: LinearFit, test_invocations: float, base: LinearFit,
              base_invocations: float, *, max_cost: float | None = None) -> Crossover:
    """The shader cost c >= 0 from which ``test`` (``test_invocations`` shaded points per
    frame) is faster than ``base``, from the two fits; ``max_cost`` (the largest cost
    measured) only adds a note when c* lies beyond it."""
    k_t, var_kt = _per_cost(test, test_invocations)
    k_b, var_kb = _per_cost(base, base_invocations)
    da, dk = test.intercept_ms - base.intercept_ms, k_b - k_t  # test faster when da < dk * u
    if not all(map(math.isfinite, (da, dk))):
        return Crossover(None, math.nan, "never: a fit is not finite")
    rates = f"{k_t:.3g} vs {k_b:.3g} ms per layer"
    if dk <= 0:
        if da < dk:  # faster at cost 0 and every cost up to where the lines meet
            back = da / dk - 1 if dk < 0 else math.inf
            again = f"; slower again from cost {back:.3g}" if math.isfinite(back) else ""
            return Crossover(0.0, 0.0, f"faster at every cost from 0{again} ({rates})")
        return Crossover(None, math.nan, f"never: its fixed cost is not below the baseline's "
                         f"and its time grows at least as fast with shader cost ({rates})")
    u = da / dk  # the lines meet at 1 + c = u
    if u <= 1:
        return Crossover(0.0, 0.0, f"faster at every cost from 0 ({rates})")
    var_da = test.intercept_se ** 2 + base.intercept_se ** 2
    cov = -(test_invocations * test.covariance + base_invocations * base.covariance) / MILLION
    var_u = u ** 2 * (var_da / da ** 2 + (var_kt + var_kb) / dk ** 2 - 2 * cov / (da * dk))
    note = f"faster from cost {u - 1:.3g} ({rates})"
    if max_cost is not None and u - 1 > max_cost:
        note += f"; beyond the largest cost measured ({max_cost:g}): extrapolated"
    return Crossover(u - 1, math.sqrt(var_u) if var_u >= 0 else math.nan, note)
