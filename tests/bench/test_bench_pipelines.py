"""``jaxrender bench``'s pipelines section: every (scene, pipeline) is a row, a budget takes
repeats away from a row but never the row, and a failing pipeline is a row with its reason."""

import argparse

import pytest

from jaxrender.bench import add_arguments
from jaxrender.bench.pipelines import time_pipelines, time_row


def test_time_row_budget_caps_repeats_not_rows():
    calls = []
    call = lambda: calls.append(1) or len(calls)  # noqa: E731
    full = time_row(call, repeats=5)
    assert full["repeats"] == 5 and len(calls) == 6 and full["out"] == 1  # warm-up + 5
    calls.clear()
    capped = time_row(call, repeats=5, budget_s=0.0)
    assert capped["repeats"] == 1 and len(calls) == 2, "at least one timed call"
    assert capped["min_ms"] <= capped["median_ms"] <= capped["max_ms"]


def test_every_row_runs(tmp_path):
    rows = list(time_pipelines(["spheres:rows=1,cols=1", "no_such_scene"],
                               ["deferred", "no_such_pipeline"], 16, 8, repeats=2,
                               budget_s=0.0, compile_workers=2))
    got = [(r["scene"], r.get("pipeline"), "skipped" in r) for r in rows]
    assert got == [("spheres:rows=1,cols=1", "deferred", False),
                   ("spheres:rows=1,cols=1", "no_such_pipeline", True),
                   ("no_such_scene", None, True)], rows
    ok = rows[0]
    assert ok["repeats"] == 1 and ok["median_ms"] > 0 and ok["compile_s"] > 0, ok
    assert ok["shade_invocations"] > 0 and ok["compile_workers"] == 2
    assert "no_such_pipeline" in rows[1]["skipped"]


def test_arguments():
    p = add_arguments(argparse.ArgumentParser())
    a = p.parse_args(["--budget", "3", "--compile-workers", "2"])
    assert (a.budget, a.compile_workers) == (3.0, 2)
    assert p.parse_args([]).budget == 0.0, "no default budget"
    with pytest.raises(SystemExit):
        p.parse_args(["--compile-workers", "0"])
