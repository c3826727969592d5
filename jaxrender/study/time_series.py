"""The time fits of a study that sweeps ``shader_cost``: per (scene, camera path, pipeline
variant) one line of frame time against shading work (``time_fit.fit_line``) and the shader
cost from which it is faster than deferred (``time_fit.crossover``), written as
``time_fits.csv``, printed after the run and drawn by the ``time_work`` figure.

A series is the variant's sequences at two or more shader costs: each sequence is one point,
its shading work the mean of its frames' ``shading_work`` and its time the per-frame
``time_ms`` of the sequence. A variant's parameters other than ``shader_cost`` name its
series, so a sweep over another parameter gives one series per value.
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jaxrender.study import shader_cost, store
from jaxrender.study.time_fit import Crossover, LinearFit, crossover, fit_line, no_fit

BASELINE = "deferred"  # the full-rate pipeline each crossover is measured against
COLUMNS = ("scene", "camera_path", "pipeline", "params", "points", "shader_costs",
           "invocations", "fixed_ms", "fixed_se_ms", "slope_ms_per_mwork", "slope_se",
           "r2", "max_rel_residual", "linear", "linearity_note", "crossover_cost",
           "crossover_se", "crossover_note")


@dataclass(frozen=True)
class Series:
    scene: str
    camera_path: str
    pipeline: str
    params: str  # JSON of the variant's parameters without shader_cost
    costs: tuple  # shader cost of each point, ascending
    work: tuple  # mean shading_work per frame
    time_ms: tuple
    invocations: float  # mean shade_invocations per frame over the series
    fit: LinearFit
    crossover: Crossover | None  # against the baseline; None for the baseline itself


def _num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _points(rows: list[dict]) -> dict:
    """{series key: {shader cost: [rows]}} of the rows that carry a cost, work and a time."""
    out: dict = {}
    for r in rows:
        if not all(_num(r.get(k)) for k in (shader_cost.KEY, shader_cost.WORK, "time_ms")):
            continue
        params = {k: v for k, v in (r.get("params") or {}).items() if k != shader_cost.KEY}
        key = (r["scene"], r["camera_path"], r["pipeline"], json.dumps(params, sort_keys=True))
        out.setdefault(key, {}).setdefault(int(r[shader_cost.KEY]), []).append(r)
    return out


def fit_series(rows: list[dict], baseline: str = BASELINE) -> list[Series]:
    """The time fit of every series with two or more shader costs, and each one's crossover
    against the ``baseline`` pipeline (its label, default parameters) on the same scene and
    camera path."""
    fitted = []
    for key, by_cost in sorted(_points(rows).items(), key=lambda kv: (*kv[0][:3],
                                                                      kv[0][3] != "{}", kv[0][3])):
        if len(by_cost) < 2:
            continue
        costs = tuple(sorted(by_cost))
        mean = lambda c, col: float(np.mean([r[col] for r in by_cost[c]]))  # noqa: E731
        work = tuple(mean(c, shader_cost.WORK) for c in costs)
        times = tuple(mean(c, "time_ms") for c in costs)
        inv = float(np.mean([w / (1 + c) for w, c in zip(work, costs)]))
        fitted.append((key, costs, work, times, inv, _fit(work, times)))
    bases = {k[:2]: (fit, inv) for k, _, _, _, inv, fit in fitted
             if k[2] == baseline and k[3] == "{}"}
    out = []
    for key, costs, work, times, inv, fit in fitted:
        cross = None
        if not (key[2] == baseline and key[3] == "{}"):
            cross = _crossover(fit, inv, bases.get(key[:2]), baseline, max(costs))
        out.append(Series(*key, costs, work, times, inv, fit, cross))
    return out


def _fit(work, times) -> LinearFit:
    if len(set(work)) < 2:  # e.g. nothing shaded: the cost changes no work
        return no_fit(len(work), "no fit: the shading work is the same at every shader cost")
    return fit_line(work, times)


def _crossover(fit, inv, base, baseline: str, max_cost) -> Crossover:
    if base is None:
        return Crossover(None, math.nan, f"no {baseline} series on this scene and path")
    c = crossover(fit, inv, base[0], base[1], max_cost=max_cost)
    if not (fit.linear and base[0].linear):
        c = Crossover(c.cost, c.cost_se, c.note + "; a fit is not linear: approximate")
    return c


def table(series: list[Series]) -> list[dict]:
    """One row of ``COLUMNS`` per series."""
    out = []
    for s in series:
        f, c = s.fit, s.crossover
        out.append({
            "scene": s.scene, "camera_path": s.camera_path, "pipeline": s.pipeline,
            "params": s.params, "points": f.n, "shader_costs": " ".join(map(str, s.costs)),
            "invocations": s.invocations, "fixed_ms": f.intercept_ms,
            "fixed_se_ms": f.intercept_se, "slope_ms_per_mwork": f.slope_ms,
            "slope_se": f.slope_se, "r2": f.r2, "max_rel_residual": f.max_rel_residual,
            "linear": f.linear, "linearity_note": f.note,
            "crossover_cost": None if c is None else c.cost,
            "crossover_se": None if c is None else c.cost_se,
            "crossover_note": "baseline" if c is None else c.note,
        })
    return out


def write_csv(series: list[Series], path: Path) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in table(series):
        w.writerow(["" if r[k] is None else r[k] for k in COLUMNS])
    store.atomic_write_text(path, buf.getvalue())


def format_fits(series: list[Series]) -> str:
    """The fits as a text table: fixed cost and slope with their errors, crossover."""
    heads = ["scene", "pipeline", "fixed ms", "ms / M layer evals", "R^2", "linear",
             f"faster than {BASELINE} from cost"]
    lines = []
    for s in series:
        f, c = s.fit, s.crossover
        name = s.pipeline + ("" if s.params == "{}" else " " + s.params)
        cross = "(baseline)" if c is None else (
            "never" if c.cost is None else _pm(c.cost, c.cost_se, ".3g"))
        lines.append([f"{s.scene}/{s.camera_path}", name, _pm(f.intercept_ms, f.intercept_se),
                      _pm(f.slope_ms, f.slope_se, ".4g"), f"{f.r2:.4f}",
                      "yes" if f.linear else "NO", cross])
    widths = [max(len(x) for x in col) for col in zip(heads, *lines)]
    fmt = lambda cells: "  ".join(  # noqa: E731
        c.ljust(w) if i < 2 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths)))
    notes = [f"  {s.scene}/{s.pipeline}: {s.fit.note}" for s in series if not s.fit.linear]
    return "\n".join([fmt(heads), fmt(["-" * w for w in widths]), *map(fmt, lines),
                      *(["not linear:"] + notes if notes else [])])


def _pm(v: float, se: float, spec: str = ".3f") -> str:
    return f"{v:{spec}}" + ("" if not math.isfinite(se) or se == 0 else f" ± {se:{spec}}")
