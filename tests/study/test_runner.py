"""The runner end to end on a tiny study with fake scenes, pipelines and metrics."""

import csv
import dataclasses
import json
import os


from jaxrender.figures import draw_run_figures
from jaxrender.study import store
from jaxrender.study.runner import run_study
from jaxrender.study.schema import load_study

REQUIRED = ("scene", "camera_path", "pipeline", "params", "frame", "rmse", "psnr", "mssim",
            "flip", "delta_e", "temporal_error", "shade_invocations", "helper_lanes",
            "covered_pixels", "time_ms")


def _run(study_file, out, figures=True, **kw):
    study = load_study(study_file)
    logs = []
    res = run_study(study, out, progress=False, log=logs.append, **kw)
    if figures:
        draw_run_figures(res, log=logs.append)
    return res, logs


def test_end_to_end(tiny_study, tmp_path):
    out = tmp_path / "run"
    res, logs = _run(tiny_study, out)
    # 2 scenes x 1 path x 3 variants (flat levels 4, 16; coarse) x 3 frames
    assert res.computed == 6 and res.skipped == 0
    assert len(res.rows) == 18
    for name in ("results.jsonl", "results.csv", "study.toml", "environment.json",
                 "summary.csv"):
        assert (out / name).is_file(), name
    with open(out / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 18
    assert set(REQUIRED) <= set(rows[0])
    assert {r["pipeline"] for r in rows} == {"flat", "coarse"}
    assert {r["params"] for r in rows} == {'{"levels":4}', '{"levels":16}',
                                           '{"levels":2,"noise":0.01}'}
    seq_te = {}
    for r in rows:
        assert float(r["psnr"]) > 0 and float(r["time_ms"]) > 0
        assert int(r["covered_pixels"]) == 24 * 16
        seq_te.setdefault(r["seq"], set()).add(r["temporal_error"])
    assert all(len(v) == 1 for v in seq_te.values())  # repeated on each row of a sequence
    # one image per saved frame per sequence, plus the references
    assert len(list((out / "images").glob("*__f0.npz"))) == 6 + 2
    figs = sorted(p.name for p in (out / "figures").glob("*.png"))
    for prefix in ("image_grid__tiny__", "pareto_time__tiny", "pareto_count__tiny",
                   "temporal__tiny__", "dacs_decisions__", "object_space_marking__",
                   "tads_samples__", "visbuffer_waves__tiny", "summary_table"):
        assert any(f.startswith(prefix) for f in figs), prefix
    assert len(list((out / "figures").glob("*.pdf"))) == len(figs)
    assert any("PSNR" in line for line in logs)  # the summary table
    # the resolved config loads back to the same study
    again = load_study(out / "study.toml")
    assert again.variants == load_study(tiny_study).variants
    assert again.paths == load_study(tiny_study).paths


def test_each_sweep_point_renders_with_its_own_parameters(tiny_study, tmp_path):
    """The points of a sweep share a label; each must still get its own compiled program."""
    res, _ = _run(tiny_study, tmp_path / "run", figures=False)
    inv = {}
    for r in res.rows:
        if r["pipeline"] == "flat":
            inv.setdefault(r["params"]["levels"], set()).add(r["shade_invocations"])
    # the fake pipeline shades covered * min(levels, 16) // 16 pixels
    assert max(inv[4]) < min(inv[16]), f"levels 4 and 16 rendered alike: {inv}"


def test_resume_recomputes_nothing_stored(tiny_study, tmp_path, monkeypatch):
    out = tmp_path / "run"
    _run(tiny_study, out, figures=False)
    path = out / "results.jsonl"
    lines = path.read_bytes().split(b"\n")[:-1]
    assert len(lines) == 18
    # simulate a kill mid-sequence: the last sequence lost a full row and half of another
    path.write_bytes(b"\n".join(lines[:-2]) + b"\n" + lines[-2][: len(lines[-2]) // 2])
    assert len(store.read_rows(path)) == 16  # the partial line is ignored

    calls = []
    from jaxrender.study import runner

    real = runner.run_sequence

    def counting(study, scene, spec, p, cams, variant, *a, **k):
        calls.append((spec.label, variant.params_json))
        return real(study, scene, spec, p, cams, variant, *a, **k)

    monkeypatch.setattr(runner, "run_sequence", counting)
    res, logs = _run(tiny_study, out, figures=False)
    assert len(calls) == 1  # only the interrupted sequence
    assert res.skipped == 5 and res.computed == 1
    assert any("partial last line" in line for line in logs)
    assert len(res.rows) == 18
    assert path.read_bytes().endswith(b"\n")
    # a third run computes nothing; --force recomputes everything
    calls.clear()
    res, _ = _run(tiny_study, out, figures=False)
    assert calls == [] and res.computed == 0
    res, _ = _run(tiny_study, out, figures=False, force=True)
    assert len(calls) == 6
    assert len(store.read_rows(path)) == 18


def test_reference_cached(tiny_study, tmp_path, monkeypatch):
    from jaxrender.pipelines import registry
    from tests.study import doubles

    calls = []

    def counted(scene, camera, cfg):
        calls.append(1)
        return doubles.render_reference(scene, camera, cfg)

    p = registry.REGISTRY["reference"]
    monkeypatch.setitem(registry.REGISTRY, "reference", dataclasses.replace(p, step=registry.FrameStep(counted)))
    _run(tiny_study, tmp_path / "a", figures=False)
    first = len(calls)
    assert first > 0
    _run(tiny_study, tmp_path / "b", figures=False)  # new output dir, same references
    assert len(calls) == first
    assert len(list((tmp_path / "cache" / "reference").glob("*.npz"))) == 6


def test_convergence_warning(tiny_study, tmp_path, monkeypatch):
    from jaxrender.pipelines import registry
    from tests.study import doubles
    from jaxrender.types import Frame

    def poor(scene, camera, cfg):
        f = doubles.render_reference(scene, camera, cfg)
        return Frame(f.image, {"convergence_psnr": 20.0}, {})

    p = registry.REGISTRY["reference"]
    monkeypatch.setitem(registry.REGISTRY, "reference", dataclasses.replace(p, step=registry.FrameStep(poor)))
    tiny_study.write_text(tiny_study.read_text() + "\n[reference]\ncheck_convergence = true\n")
    res, logs = _run(tiny_study, tmp_path / "run", figures=False)
    assert res.warnings and "may not be converged" in res.warnings[0]
    assert any(line.startswith("warning:") for line in logs)


KILL_SCRIPT = """
import sys, time
import pytest
from jaxrender.study import store, runner
from tests.study import doubles
from jaxrender.study.schema import load_study

mp = pytest.MonkeyPatch()
doubles.install(mp)
real = store.ResultStore.append
def slow(self, rows):
    real(self, rows)
    print("appended", flush=True)
    time.sleep(0.5)
mp.setattr(store.ResultStore, "append", slow)
runner.run_study(load_study(sys.argv[1]), sys.argv[2], progress=False,
                 log=lambda *a: None)  # stdout carries only the "appended" markers
"""


def test_kill_9_leaves_no_half_row(tiny_study, tmp_path):
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "run"
    script = tmp_path / "child.py"
    script.write_text(KILL_SCRIPT)
    env = {**os.environ, "JAX_PLATFORMS": "cpu", "PYTHONPATH": os.getcwd()}
    child = subprocess.Popen([sys.executable, str(script), str(tiny_study), str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env)
    assert child.stdout.readline().strip() == b"appended"  # one sequence is stored
    time.sleep(0.1)
    child.send_signal(signal.SIGKILL)
    child.wait()
    child.stdout.close()
    stored = store.read_rows(out / "results.jsonl")
    assert 3 <= len(stored) < 18 and len(stored) % 3 == 0  # whole sequences only
    done = {r["seq"] for r in stored}
    res, _ = _run(tiny_study, out, figures=False)
    assert res.skipped == len(done) and res.computed == 6 - len(done)
    assert len(res.rows) == 18
    assert len(store.read_rows(out / "results.jsonl")) == 18
    # the same results as a run never interrupted (timings aside)
    whole, _ = _run(tiny_study, tmp_path / "whole", figures=False)
    skip = {"time_ms", "time_ms_single", "sequence_ms", "compile_ms", "compile_ms_single",
            "compile_ms_timed"}
    key = lambda r: (r["seq"], r["frame"])  # noqa: E731
    same = lambda r: json.dumps({k: v for k, v in r.items() if k not in skip},  # noqa: E731
                                sort_keys=True)  # as JSON, so that NaN equals NaN
    assert {key(r): same(r) for r in res.rows} == {key(r): same(r) for r in whole.rows}


def test_real_metrics(fake, tiny_study, tmp_path, monkeypatch):
    """The runner with jaxrender.metrics itself (display-referred) on the fake pipelines."""
    import jaxrender.metrics as m
    from tests.study import doubles

    for name, metric in doubles.REAL_METRICS.items():  # undo the fakes the fixture installed
        monkeypatch.setitem(m.METRICS, name, metric)
    study = load_study(tiny_study).with_overrides(frames=2)
    res = run_study(study, tmp_path / "real", progress=False, log=lambda s: None)
    for r in res.rows:
        assert 0 < r["psnr"] < 80 and 0 < r["mssim"] <= 1 and 0 <= r["flip"] <= 1
        assert r["delta_e"] >= 0 and r["temporal_error"] >= 0
    coarse = [r["psnr"] for r in res.rows if r["pipeline"] == "coarse"]
    fine = [r["psnr"] for r in res.rows if r["params"] == {"levels": 16}]
    assert max(coarse) < min(fine)  # fewer quantisation levels, lower PSNR



def test_rows_timed_otherwise_are_not_resumed(tiny_study, tmp_path):
    """A run resumed with another [timing] outputs computes its sequences again rather than
    mix times with and without the counts; rows timed with them keep their old keys."""
    from jaxrender.study.sequence_run import sequence_key

    study = load_study(tiny_study)
    spec, path, variant = study.scenes[0], study.paths[0], study.variants[0]
    keys = {o: sequence_key(dataclasses.replace(
        study, timing=dataclasses.replace(study.timing, outputs=o)), spec, path, variant)
        for o in ("images", "all")}
    assert keys["images"] != keys["all"]
    legacy = store.seq_key(
        [spec.source, spec.params, spec.file_hash], [path.name, path.type, path.frames,
                                                     path.params],
        [variant.label, variant.type, variant.params_json], study.resolution,
        [study.reference.pipeline, study.reference.params], sorted(study.metrics),
        study.warmup_frames)
    assert keys["all"] == legacy, "rows timed with the counts changed their key"
    first = run_study(study, tmp_path / "run", progress=False, log=lambda *_: None)
    assert {r["timed_outputs"] for r in first.rows} == {"images"}
    other = dataclasses.replace(study, timing=dataclasses.replace(study.timing, outputs="all"))
    again = run_study(other, tmp_path / "run", progress=False, log=lambda *_: None)
    assert again.skipped == 0 and again.computed == first.computed
    assert {r["timed_outputs"] for r in again.rows} == {"all"}
