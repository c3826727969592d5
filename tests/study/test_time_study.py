"""The bundled time_follows_work study end to end at a tiny size: two pipelines at two shader
costs on one scene, real pipelines; rows carry the cost and the work, the run writes the fits
and the figure draws them."""

import csv
import dataclasses

from jaxrender.figures import render_figures
from jaxrender.study import load_study, run_study, time_series

COSTS = (0, 16)
PIPELINES = ("deferred", "checkerboard")


def _tiny(study):
    pipes = []
    for p in study.pipelines:
        if p.label in PIPELINES:
            vs = tuple(v for v in p.variants if dict(v.params)["shader_cost"] in COSTS)
            pipes.append(dataclasses.replace(p, variants=vs))
    study = study.with_overrides(frames=1, resolution="32x18")
    return dataclasses.replace(study, scenes=study.scenes[:1], pipelines=tuple(pipes))


def test_time_follows_work_tiny(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "cache"))
    full = load_study("time_follows_work")
    assert {dict(v.params)["shader_cost"] for v in full.variants} == {0, 16, 64, 256, 1024}
    assert {p.type for p in full.pipelines} >= {"deferred", "checkerboard", "dacs",
                                                "object_space", "visbuffer", "forward"}
    study = _tiny(full)
    lines: list = []
    res = run_study(study, tmp_path / "out", progress=False, log=lines.append)
    summary = next(ln for ln in lines if ln.startswith("pipeline"))
    assert "time ms: per frame, timed with the images alone" in summary, summary
    assert len(res.rows) == len(PIPELINES) * len(COSTS)
    for r in res.rows:
        # Timed with the images alone (the default), counted by the instrumented program
        assert r["timed_outputs"] == "images" and r["compile_ms_timed"] > 0, r
        assert r["shader_cost"] == r["params"]["shader_cost"], r
        assert r["shading_work"] == r["shade_invocations"] * (1 + r["shader_cost"]), r
    by_cost = {(r["pipeline"], r["shader_cost"]): r for r in res.rows}
    for p in PIPELINES:  # the cost changes the work per point, not the points shaded
        assert by_cost[p, 0]["shade_invocations"] == by_cost[p, 16]["shade_invocations"], p
    assert [(s.pipeline, s.costs) for s in res.time_fits] == [
        ("checkerboard", COSTS), ("deferred", COSTS)]
    with open(tmp_path / "out" / "time_fits.csv", newline="") as f:
        fits = list(csv.DictReader(f))
    assert tuple(fits[0]) == time_series.COLUMNS
    assert [r["pipeline"] for r in fits] == ["checkerboard", "deferred"]
    assert fits[1]["crossover_note"] == "baseline" and fits[0]["crossover_note"]
    made = render_figures(tmp_path / "out", ("time_work",), log=lambda *_: None, workers=1)
    assert [p.name for p in made] == ["time_work__terrain__static.png",
                                      "time_work__terrain__static.pdf"]
