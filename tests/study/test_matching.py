"""Matched sweep points: the bisection against a NumPy-free oracle (a step function it must
land on), and end to end on a toy scene through the real DACS and checkerboard pipelines."""

from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest

from jaxrender.errors import StudyError
from jaxrender.study import matching, programs
from jaxrender.study.runner import run_study
from jaxrender.study.schema import load_study


def test_bisection_lands_on_a_step_function_within_one_step(rng):
    # Counts as DACS makes them: how many of 500 variances lie at or above the threshold.
    variances = np.sort(rng.uniform(0.0, 0.05, 500))
    count = lambda thr: float(np.sum(variances >= thr))  # noqa: E731
    target = float(rng.integers(50, 450))
    points = [(v, count(v)) for v in (0.0, 1e-3, 1e-2, 0.1)]
    out = matching.bisect(count, points, target, 0.0, 60)
    assert abs(out.reached - target) <= 1.0, f"reached {out.reached}, target {target}"
    assert out.reached == count(out.value), "the reported quantity is the probe's own"


def test_bisection_refuses_a_target_beyond_the_sweep():
    with pytest.raises(matching.OutOfRange, match="reaches 2 .. 8"):
        matching.bisect(lambda x: x, [(2.0, 2.0), (8.0, 8.0)], 9.0, 0.5, 10)


@pytest.mark.parametrize("a, b", [(0.0, 1.0), (1e-4, 1.0), (0.5, math.inf), (-2.0, 1.0)])
def test_midpoint_lies_strictly_inside(a, b):
    assert a < matching.midpoint(a, b) < b


STUDY = """
name = "match"
resolution = "32x18"
metrics = ["rmse", "psnr", "mssim"]
figures = ["summary_table"]
scenes = [{{ name = "spheres", params = {{ rows = 1, cols = 2 }} }}]
[timing]
warmup = 0
repeats = 1
single_frame = false
# The times are not the subject: one program per variant, its counts and views timed too.
outputs = "all"
[reference]
pipeline = "deferred"
[[pipelines]]
type = "checkerboard"
params = {{ temporal = false }}
[[pipelines]]
type = "dacs"
sweep = {{ threshold = {sweep} }}
match = {{ against = "checkerboard", on = "shade_invocations", probes = 40 }}
"""


def _write(tmp_path, sweep: str):
    p = tmp_path / "match.toml"
    p.write_text(textwrap.dedent(STUDY.format(sweep=sweep)))
    return p


@pytest.fixture
def cache(monkeypatch, tmp_path_factory):
    # One cache for the file: its tests load the programs and references stored by the first.
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path_factory.getbasetemp() / "match_cache"))


def test_match_lands_within_one_pixel_of_checkerboards_count(tmp_path, cache, monkeypatch):
    compiled = []
    real = programs.compile_variant
    monkeypatch.setattr(programs, "compile_variant", lambda study, scene, cams, v, **kw: (
        compiled.append(v.type), real(study, scene, cams, v, **kw))[1])
    study = load_study(_write(tmp_path, "[0.0, 10.0]"))
    run = run_study(study, tmp_path / "run", progress=False, log=lambda *_: None)
    # The sweep's two points and the probes share one program: the threshold is its argument.
    assert sorted(compiled) == ["checkerboard", "dacs"], compiled
    by = {r["pipeline"]: r for r in run.rows}
    target = by["checkerboard"]["shade_invocations"]
    got = by["dacs@checkerboard.shade_invocations"]
    assert abs(got["shade_invocations"] - target) <= 1, (
        f"DACS at threshold {got['params']['threshold']} shades {got['shade_invocations']}, "
        f"checkerboard {target}")
    assert got["match_target"] == target and got["match_value"] == got["shade_invocations"]
    assert 0.0 < got["params"]["threshold"] < 10.0
    # Rerun: the matched point is stored, nothing is bisected again.
    again = run_study(study, tmp_path / "run", progress=False, log=lambda *_: None)
    assert again.computed == 0
    assert [r for r in again.rows if r["pipeline"] == got["pipeline"]][0]["seq"] == got["seq"]
    # A run interrupted before its match: the sweep is stored, so its program is compiled
    # for the match alone, and the bisection lands where it did.
    store = tmp_path / "run" / "results.jsonl"
    kept = [line for line in store.read_text().splitlines() if got["seq"] not in line]
    store.write_text("\n".join(kept) + "\n")
    logs = []
    third = run_study(study, tmp_path / "run", progress=False, log=logs.append)
    redo = [r for r in third.rows if r["pipeline"] == got["pipeline"]][0]
    assert (redo["params"], redo["shade_invocations"]) == (got["params"],
                                                           got["shade_invocations"])
    assert any(line.startswith("match dacs@checkerboard") for line in logs), logs


def test_match_refuses_a_target_outside_the_sweep_naming_the_key(tmp_path, cache):
    # Threshold 0 shades every covered pixel, 1e-9 nearly all: never checkerboard's half.
    study = load_study(_write(tmp_path, "[0.0, 1e-9]"))
    with pytest.raises(StudyError, match=r"pipelines\[1\]\.match: .*outside the sweep.*"
                       r"widen pipelines\[1\]\.sweep\.threshold"):
        run_study(study, tmp_path / "run", progress=False, log=lambda *_: None)


@pytest.mark.parametrize("edit, key", [
    ('sweep = {{ threshold = {sweep} }}', "pipelines[1].sweep.spacing"),
    ('against = "checkerboard"', "pipelines[1].match.against"),
    ('on = "shade_invocations"', "pipelines[1].match.on"),
])
def test_match_validation_names_the_key(tmp_path, edit, key):
    bad = {"pipelines[1].sweep.spacing": 'sweep = {{ spacing = [4, 8] }}',
           "pipelines[1].match.against": 'against = "dacs"',
           "pipelines[1].match.on": 'on = "flip"'}[key]
    text = STUDY.replace(edit, bad).format(sweep="[0.0, 10.0]")
    p = tmp_path / "bad.toml"
    p.write_text(textwrap.dedent(text))
    with pytest.raises(StudyError) as e:
        load_study(p)
    assert f"bad.toml: {key}:" in str(e.value), str(e.value)


def test_outside_nearest_takes_the_closest_sweep_end_and_says_so():
    out = matching.bisect(lambda x: x, [(2.0, 2.0), (8.0, 8.0)], 9.0, 0.5, 10, nearest=True)
    assert (out.value, out.reached, out.probes, out.bracketed) == (8.0, 8.0, 0, False)


def test_bundled_dacs_study_round_trips_its_matches(tmp_path):
    from jaxrender.study.specs import to_toml

    study = load_study("dacs_vs_checkerboard")
    dacs = next(p for p in study.pipelines if p.label == "dacs")
    assert [m.on for m in dacs.match] == ["shade_invocations", "shade_invocations", "mssim",
                                          "time_ms"]
    p = tmp_path / "study.toml"
    p.write_text(to_toml(study))
    again = load_study(p)
    assert next(x for x in again.pipelines if x.label == "dacs").match == dacs.match
