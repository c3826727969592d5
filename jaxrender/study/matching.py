"""Matched points of a sweep: the value of a pipeline entry's one swept parameter at which a
measured quantity equals another pipeline's, found by bisection inside the study.

A pipeline entry sweeping one parameter may carry ``match`` tables::

    [[pipelines]]
    type = "dacs"
    sweep = { threshold = [0.0, 0.001, 0.01, 0.1, inf] }
    match = { against = "checkerboard", on = "shade_invocations" }

``on`` is a row column (a metric, a count such as ``shade_invocations``, or ``time_ms``), its
value per sequence the mean over the scored frames. For each scene and camera path the target
is the ``against`` pipeline's value; the sweep's own points bracket it (a target the sweep
does not reach is refused, naming the match's key and the sweep's), and bisection between the
two bracketing values (geometric where both are positive, since thresholds span decades)
renders probes until one lands within ``tolerance`` of the target, the bracket closes or
``probes`` renders are spent. The point closest to the target is rendered once more under the
match's ``label``, and its rows say what was aimed at and what was reached (``COLUMNS``).

The swept parameter must be one the compiled program takes as an argument (the config's
``TRACED_FIELDS``), so every probe runs the one program already compiled for the sweep.
Bisection assumes the quantity is monotone in the parameter between the bracketing points;
a measured time is not exactly, so a time match reports the time its final render measured.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from jaxrender.metrics import METRICS
from jaxrender.study import backend
from jaxrender.study.specs import MatchSpec
from jaxrender.study.tables import Checker, read_table

# Columns of a matched point's rows.
COLUMNS = ("match_against", "match_on", "match_target", "match_value", "match_param",
           "match_probes", "match_reached")
OUTSIDE = ("refuse", "nearest")
_CLOSED = 1e-6  # a bracket this narrow (relative) is closed


# ------------------------------------------------------------------ validation


def match_key(i: int, j: int, n: int) -> str:
    """The key path of entry ``i``'s ``j``-th of ``n`` match tables."""
    return f"pipelines[{i}].match" + (f"[{j}]" if n > 1 else "")


def parse(ck: Checker, raw, path: str, label: str, ptype: str, sweep: dict) -> tuple:
    """The entry's ``match`` tables (one table or a list of them) as MatchSpecs; the entry must
    sweep one numeric parameter of its pipeline's TRACED_FIELDS, at two values or more."""
    if raw is None:
        return ()
    where = f"{path}.match"
    items = [raw] if isinstance(raw, dict) else ck.list_(raw, where)
    if len(sweep) != 1:
        ck.fail(where, f"a match bisects one swept parameter; the entry sweeps "
                f"{len(sweep)} ({', '.join(sweep) or 'none'}): sweep exactly one")
    (key, values), = sweep.items()
    traced = backend.pipeline(ptype).config_cls.TRACED_FIELDS
    if key not in traced:
        ck.fail(f"{path}.sweep.{key}", f"a match bisects a parameter the compiled program "
                f"takes as an argument; {ptype!r} takes {', '.join(traced) or 'none'}, "
                f"not {key!r}")
    if len(values) < 2 or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                  for v in values):
        ck.fail(f"{path}.sweep.{key}", "a match needs at least two numbers to bisect between")
    out = []
    for j, item in enumerate(items):
        at = where + (f"[{j}]" if len(items) > 1 else "")
        d = read_table(ck, item, at, MatchSpec, defaults={"label": None})
        against = ck.str_(d["against"], f"{at}.against")
        on = ck.str_(d["on"], f"{at}.on")
        m_label = ck.str_(d["label"] or f"{label}@{against}.{on}", f"{at}.label")
        tol = ck.num(d["tolerance"], f"{at}.tolerance")
        if tol < 0:
            ck.fail(f"{at}.tolerance", f"expected a number >= 0, got {tol}")
        if d["outside"] not in OUTSIDE:
            ck.fail(f"{at}.outside", f"expected one of {', '.join(OUTSIDE)}, got "
                    f"{d['outside']!r}")
        out.append(MatchSpec(m_label, against, on, tol, d["probes"], d["outside"]))
    return tuple(out)


def check(ck: Checker, pipelines, metrics) -> None:
    """Every match aims at another entry of the study with one variant, measures a metric the
    study computes (or a count or time column) and has a label no entry or match uses."""
    labels = {p.label: p for p in pipelines}
    used = set(labels)
    for i, p in enumerate(pipelines):
        for j, m in enumerate(p.match):
            at = match_key(i, j, len(p.match))
            target = labels.get(m.against)
            if target is None or target is p:
                ck.fail(f"{at}.against", f"no other pipeline labelled {m.against!r}; labels: "
                        f"{', '.join(x for x in labels if x != p.label)}")
            if len(target.variants) != 1:
                ck.fail(f"{at}.against", f"{m.against!r} has {len(target.variants)} variants;"
                        f" a match needs one measurement to aim at")
            if m.on in METRICS and m.on not in metrics:
                ck.fail(f"{at}.on", f"{m.on!r} is not among the study's metrics: "
                        f"{', '.join(metrics)}")
            if m.label in used:
                ck.fail(f"{at}.label", f"pipeline label {m.label!r} is used twice")
            used.add(m.label)


def entries(study) -> list[tuple[str, object, MatchSpec]]:
    """(key path, pipeline entry, match) of every match of the study, in file order."""
    return [(match_key(i, j, len(p.match)), p, m) for i, p in enumerate(study.pipelines)
            for j, m in enumerate(p.match)]


# ------------------------------------------------------------------ measuring and bisecting


class OutOfRange(ValueError):
    """The target lies beyond what the sweep's points reach."""


def mean_of(rows: list[dict], column: str) -> float | None:
    """The mean of ``column`` over ``rows`` (a sequence's scored frames); None if any row
    lacks it as a number."""
    vals = [r.get(column) for r in rows]
    if not vals or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                           for v in vals):
        return None
    return float(sum(vals) / len(vals))


def midpoint(a: float, b: float) -> float:
    """A point strictly between a < b where one exists: geometric for positive finite ends,
    a sixteenth of b above zero, 16 a (or 1) below infinity, else arithmetic."""
    if math.isinf(b):
        return a * 16.0 if a > 0 else max(a + 1.0, 1.0)
    if a > 0:
        return math.sqrt(a * b)
    if a == 0:
        return b / 16.0
    return 0.5 * (a + b)


@dataclass
class Outcome:
    value: float  # the parameter value closest to the target
    reached: float  # the quantity measured there
    probes: int  # renders the bisection spent (the final render not included)
    bracketed: bool = True  # False: the target lies beyond the sweep (outside = "nearest")


def bisect(probe: Callable[[float], float], points: list[tuple[float, float]], target: float,
           tolerance: float, probes: int, *, nearest: bool = False) -> Outcome:
    """``points``: (parameter, quantity) of the sweep; ``probe(value) -> quantity`` renders.
    Raises OutOfRange when no two neighbouring points (in parameter order) bracket the target
    (widened by the tolerance), or with ``nearest`` returns the closest point unprobed."""
    pts = sorted(points)
    qs = [q for _, q in pts]
    if not (min(qs) - tolerance <= target <= max(qs) + tolerance):
        if nearest:
            best = min(pts, key=lambda p: abs(p[1] - target))
            return Outcome(best[0], best[1], 0, bracketed=False)
        raise OutOfRange(f"the sweep reaches {min(qs):.6g} .. {max(qs):.6g} over "
                         f"{pts[0][0]:.6g} .. {pts[-1][0]:.6g}")
    best = min(pts, key=lambda p: abs(p[1] - target))
    pairs = [(p, r) for p, r in zip(pts, pts[1:]) if (p[1] - target) * (r[1] - target) <= 0]
    if not pairs:  # within the tolerance of an end only
        return Outcome(best[0], best[1], 0)
    (a, qa), (b, qb) = pairs[0]
    spent = 0
    while spent < probes and abs(best[1] - target) > tolerance:
        mid = midpoint(a, b)
        if not a < mid < b or (a > 0 and not math.isinf(b) and b - a <= _CLOSED * b):
            break
        q = probe(mid)
        spent += 1
        if abs(q - target) < abs(best[1] - target):
            best = (mid, q)
        if (qa - target) * (q - target) <= 0:
            b, qb = mid, q
        else:
            a, qa = mid, q
    return Outcome(best[0], best[1], spent)
