"""The time fits: least squares against numpy.polyfit and the generating line, the linearity
check on a bent series, the crossover against its analytic value and its error against a
Monte Carlo draw of the fits, and the series read from study rows."""

import math

import numpy as np
import pytest

from jaxrender.study import time_fit, time_series
from jaxrender.study.time_fit import LinearFit, crossover, fit_line

COSTS = np.array([0, 4, 16, 64, 256])
INVOCATIONS = 1_500_000


def _work(inv=INVOCATIONS, costs=COSTS):
    return inv * (1.0 + costs)


def test_fit_recovers_a_noisy_line(rng):
    work = np.repeat(_work(), 4)  # four timed runs per cost
    a, b, sigma = 2.5, 0.04, 0.02  # ms, ms per million layer evaluations, ms
    t = a + b * work / 1e6 + rng.normal(0.0, sigma, work.size)
    f = fit_line(work, t)
    (pb, pa), cov = np.polyfit(work / 1e6, t, 1, cov=True)
    np.testing.assert_allclose([f.intercept_ms, f.slope_ms], [pa, pb], rtol=1e-9,
                               err_msg="intercept and slope against numpy.polyfit")
    np.testing.assert_allclose([f.intercept_se, f.slope_se, f.covariance],
                               [math.sqrt(cov[1, 1]), math.sqrt(cov[0, 0]), cov[0, 1]],
                               rtol=1e-6, err_msg="standard errors against numpy.polyfit's")
    # The generating line lies within 4 standard errors (a 6e-5 chance of a false failure).
    assert abs(f.intercept_ms - a) < 4 * f.intercept_se, (f.intercept_ms, f.intercept_se)
    assert abs(f.slope_ms - b) < 4 * f.slope_se, (f.slope_ms, f.slope_se)
    # The analytic slope error for this design: sigma / sqrt(Sxx).
    x = work / 1e6
    np.testing.assert_allclose(f.slope_se, sigma / np.sqrt(np.sum((x - x.mean()) ** 2)),
                               rtol=0.5, err_msg="slope error near its expectation")
    assert f.linear and f.note == "" and f.r2 > 0.999, f


def test_exact_line_and_two_points():
    f = fit_line([1e6, 3e6], [1.0, 2.0])
    assert (f.intercept_ms, f.slope_ms) == pytest.approx((0.5, 0.5), rel=1e-12)
    assert math.isnan(f.intercept_se) and math.isnan(f.slope_se), "no error from 2 points"
    assert f.r2 == 1.0 and f.linear
    with pytest.raises(ValueError, match="two distinct"):
        fit_line([2e6, 2e6], [1.0, 1.1])
    with pytest.raises(ValueError, match="finite"):
        fit_line([1e6, 2e6], [1.0, float("nan")])


def test_a_bent_series_is_flagged(rng):
    work = _work()
    x = work / 1e6
    bent = 1.0 + 0.002 * x ** 2  # shading that gets dearer per unit as work grows
    f = fit_line(work, bent)
    assert not f.linear and "off the line" in f.note, f
    assert f.max_rel_residual > time_fit.REL_TOL
    # The same series with 1% noise on a line passes.
    line = 1.0 + 0.5 * x
    noisy = line * (1 + rng.normal(0, 0.01, line.size))
    assert fit_line(work, noisy).linear
    # A saturating series (time stops following work) fails too.
    sat = 1.0 + 10 * (1 - np.exp(-x / 50.0))
    assert not fit_line(work, sat).linear


def _line(a, b, se_a=0.0, se_b=0.0, cov=0.0):
    return LinearFit(5, a, se_a, b, se_b, cov, 1.0, 0.0, True, "")


def test_crossover_analytic():
    base = _line(2.0, 0.05)  # deferred: 2 ms fixed
    # Half the invocations, 3 ms fixed: equal where 3 + 0.05*0.75 u = 2 + 0.05*1.5 u.
    inv_b, inv_t = 1.5e6, 0.75e6
    c = crossover(_line(3.0, 0.05), inv_t, base, inv_b)
    u = (3.0 - 2.0) / (0.05 * 1.5 - 0.05 * 0.75)
    assert c.cost == pytest.approx(u - 1, rel=1e-12) and "faster from cost" in c.note
    assert c.cost_se == 0.0
    # Beyond the measured costs: the same value, with a note.
    far = crossover(_line(3.0, 0.05), inv_t, base, inv_b, max_cost=4)
    assert far.cost == pytest.approx(u - 1) and "extrapolated" in far.note
    # Cheaper fixed cost and cheaper work: faster from cost 0.
    assert crossover(_line(1.0, 0.05), inv_t, base, inv_b).cost == 0.0
    # Dearer fixed cost and a steeper slope per cost unit: never.
    never = crossover(_line(3.0, 0.2), inv_t, base, inv_b)
    assert never.cost is None and never.note.startswith("never")
    # Cheaper fixed cost, steeper per cost unit: faster from 0, slower again where they meet.
    back = crossover(_line(1.0, 0.2), inv_t, base, inv_b)
    want = (1.0 - 2.0) / (0.05 * 1.5 - 0.2 * 0.75) - 1
    assert back.cost == 0.0 and f"slower again from cost {want:.3g}" in back.note, back


def test_crossover_error_against_monte_carlo(rng):
    cov_t = np.array([[0.01, -0.0002], [-0.0002, 0.00001]])  # (intercept, slope)
    cov_b = np.array([[0.004, -0.0001], [-0.0001, 0.000004]])
    mt, mb = (3.0, 0.05), (2.0, 0.05)
    test = _line(*mt, math.sqrt(cov_t[0, 0]), math.sqrt(cov_t[1, 1]), cov_t[0, 1])
    base = _line(*mb, math.sqrt(cov_b[0, 0]), math.sqrt(cov_b[1, 1]), cov_b[0, 1])
    inv_t, inv_b = 0.75e6, 1.5e6
    c = crossover(test, inv_t, base, inv_b)
    dt = rng.multivariate_normal(mt, cov_t, 200_000)
    db = rng.multivariate_normal(mb, cov_b, 200_000)
    u = (dt[:, 0] - db[:, 0]) / (db[:, 1] * inv_b / 1e6 - dt[:, 1] * inv_t / 1e6)
    np.testing.assert_allclose(c.cost_se, np.std(u), rtol=0.1,
                               err_msg="delta-method error of the crossover vs Monte Carlo")


def _rows(pipeline, a, b, inv, costs=(0, 4, 16), scene="s", params=None):
    return [{"scene": scene, "camera_path": "static", "pipeline": pipeline,
             "params": {**(params or {}), "shader_cost": c}, "shader_cost": c,
             "shading_work": inv * (1 + c), "shade_invocations": inv,
             "time_ms": a + b * inv * (1 + c) / 1e6, "frame": 0} for c in costs]


def test_series_from_rows():
    rows = (_rows("deferred", 2.0, 0.05, 1.5e6) + _rows("checkerboard", 3.0, 0.05, 0.75e6)
            + _rows("deferred", 2.0, 0.05, 1.5e6, params={"msaa": 4})
            + _rows("forward", 9.0, 0.05, 1.6e6, costs=(0,))  # one cost: no series
            + [{"scene": "s", "camera_path": "static", "pipeline": "x", "params": {},
                "time_ms": 1.0, "frame": 0}])  # no shader cost: not a time row
    series = time_series.fit_series(rows)
    names = [(s.pipeline, s.params) for s in series]
    assert names == [("checkerboard", "{}"), ("deferred", "{}"), ("deferred", '{"msaa": 4}')]
    cb, base, msaa = series
    assert base.crossover is None, "the baseline has no crossover"
    assert cb.fit.intercept_ms == pytest.approx(3.0) and cb.fit.slope_ms == pytest.approx(0.05)
    assert cb.invocations == pytest.approx(0.75e6)
    assert cb.crossover.cost == pytest.approx(1.0 / (0.05 * 0.75) - 1)
    assert msaa.crossover.cost is None, "equal lines never cross"
    table = time_series.table(series)
    assert set(table[0]) == set(time_series.COLUMNS)
    text = time_series.format_fits(series)
    assert "fixed ms" in text and "(baseline)" in text
    lone = time_series.fit_series(_rows("checkerboard", 3.0, 0.05, 0.75e6))
    assert lone[0].crossover.cost is None and "no deferred" in lone[0].crossover.note


def test_a_series_without_varying_work_is_kept_unfitted():
    rows = _rows("deferred", 2.0, 0.05, 1.5e6) + _rows("checkerboard", 1.0, 0.0, 0.0)
    cb, base = time_series.fit_series(rows)
    assert cb.pipeline == "checkerboard" and not cb.fit.linear and "no fit" in cb.fit.note
    assert math.isnan(cb.fit.intercept_ms) and cb.crossover.cost is None
    assert base.fit.linear
