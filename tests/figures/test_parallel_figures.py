"""Figures drawn by worker processes are the figures drawn serially: same paths, same log
lines, byte-identical PNG and PDF files; a failing figure surfaces in the parent by name."""

import multiprocessing.spawn
import traceback
from functools import partial

import pytest

from jaxrender.figures import parallel, plots
from jaxrender.figures.make import render_figures
from jaxrender.spawning import main_hidden

# One scene, a one-frame path (so "temporal" has nothing to draw), two variants.
STUDY = """
name = "figs"
resolution = "24x16"
save_frames = [0]
scenes = ["tiny"]

[timing]
warmup = 0
repeats = 1

[[paths]]
name = "still"
type = "static"
frames = 1

[[pipelines]]
type = "flat"
sweep = { levels = [4, 16] }
"""

# the array-heavy figure, a small one, and a skipped one between them
NAMES = ("image_grid", "temporal", "pareto_time")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from jaxrender.study import load_study, run_study
    from tests.study import doubles

    root = tmp_path_factory.mktemp("figs")
    (root / "configs").mkdir()
    (root / "figs.toml").write_text(STUDY)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("JAXRENDER_CACHE", str(root / "cache"))
        doubles.install(mp)
        run_study(load_study(root / "figs.toml"), root / "run", progress=False,
                  log=lambda s: None)
    return root / "run"


def test_parallel_equals_serial(run_dir, tmp_path):
    outs = {}
    for w in (1, 2):  # 2 workers even on a machine where None would choose serial
        logs = []
        made = render_figures(run_dir, NAMES, out_dir=tmp_path / f"w{w}", log=logs.append,
                              workers=w)
        outs[w] = (made, logs)
    (serial, serial_logs), (par, par_logs) = outs[1], outs[2]
    assert [p.relative_to(tmp_path / "w1") for p in serial] == \
        [p.relative_to(tmp_path / "w2") for p in par]
    assert [p.name for p in serial] == [
        "image_grid__tiny__still.png", "image_grid__tiny__still.pdf",
        "pareto_time__tiny.png", "pareto_time__tiny.pdf"]
    assert serial_logs == ["figure temporal: nothing to draw in this run (skipped)",
                           f"2 figure(s) in {tmp_path / 'w1'}"]
    assert par_logs == [serial_logs[0], f"2 figure(s) in {tmp_path / 'w2'}"]
    for a, b in zip(serial, par):
        assert a.stat().st_size > 0
        assert a.read_bytes() == b.read_bytes(), a.name


GOOD = partial(plots.fig_summary_table, {"title": "t", "columns": ["a"], "rows": [["x"]]})
BROKEN = partial(plots.fig_pareto, {})  # no "series": KeyError when drawn


@pytest.mark.parametrize("workers", [1, 2])
def test_failure_names_the_figure(workers, tmp_path):
    jobs = [("summary_table", GOOD, tmp_path / "ok"), ("pareto_time", BROKEN, tmp_path / "bad")]
    with pytest.raises(KeyError) as info:
        parallel.draw(jobs, workers)
    text = "".join(traceback.format_exception(info.value))
    assert "while drawing figure pareto_time (bad)" in text


def test_worker_count(monkeypatch):
    monkeypatch.setattr(parallel, "available_cpus", lambda: 2)
    assert parallel.worker_count(61) == 1  # the 2-core CI machine stays serial
    assert parallel.worker_count(61, workers=2) == 2
    monkeypatch.setattr(parallel, "available_cpus", lambda: 16)
    assert parallel.worker_count(61) == 8
    assert parallel.worker_count(5) == 1  # too few figures to pay for the workers' start
    assert parallel.worker_count(7) == 7
    assert parallel.worker_count(3, workers=8) == 3
    assert parallel.worker_count(0, workers=1) == 1
    with pytest.raises(ValueError):
        parallel.worker_count(10, workers=0)


def test_workers_do_not_import_the_main_script():
    with main_hidden():
        prep = multiprocessing.spawn.get_preparation_data("w")
    assert "init_main_from_path" not in prep and "init_main_from_name" not in prep
