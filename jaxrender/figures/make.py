"""Redraw every figure of a run directory from its stored results (no rendering)."""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

from matplotlib.figure import Figure

from jaxrender.figures import data, parallel, plots
from jaxrender.study.specs import FIGURES


def _figure_jobs(run: data.Run, name: str) -> list[tuple[str, Callable[[], Figure]]]:
    """(stem, make_figure) pairs of one figure kind: the tables are prepared here (cheap), the
    figures are drawn when ``make_figure()`` is called. Each ``make_figure`` is a picklable
    partial of a ``plots`` function and its table, so a worker process can draw it."""
    if name == "image_grid":
        return [(f"image_grid__{s}", partial(plots.fig_image_grid, t))
                for s, t in data.image_grid_panels(run)]
    if name in ("pareto_time", "pareto_count"):
        x = "time_ms" if name == "pareto_time" else "shade_invocations"
        return [(f"{name}__{s}", partial(plots.fig_pareto, data.pareto_table(run, s, x)))
                for s in data.scenes(run)]
    if name == "temporal":
        return [(f"temporal__{s}", partial(plots.fig_temporal, t))
                for s, t in data.temporal_tables(run)]
    if name == "dacs_decisions":
        return [(f"dacs_decisions__{s}", partial(plots.fig_dacs_decisions, t))
                for s, t in data.aux_tables(run, "dacs")]
    if name == "object_space_marking":
        return [(f"object_space_marking__{s}", partial(plots.fig_object_space_marking, t))
                for s, t in data.aux_tables(run, "object_space")]
    if name == "tads_samples":
        return [(f"tads_samples__{s}", partial(plots.fig_tads_samples, t))
                for s, t in data.aux_tables(run, "tads")]
    if name == "visbuffer_waves":
        return [(f"visbuffer_waves__{s}", partial(plots.fig_visbuffer_waves, t))
                for s, t in data.waves_tables(run)]
    if name == "time_work":
        return [(f"time_work__{s}", partial(plots.fig_time_work, t))
                for s, t in data.time_work_tables(run)]
    if name == "summary_table":
        return [("summary_table", partial(plots.fig_summary_table, data.summary_table(run)))]
    raise ValueError(f"unknown figure {name!r}; known: {', '.join(FIGURES)}")


def render_figures(run_dir, names=FIGURES, *, out_dir=None, log=print,
                   workers: int | None = None) -> list[Path]:
    """Draw the named figures into ``out_dir`` (default RUN_DIR/figures); figures without
    data in this run are skipped with a note. Returns the written files (PNG, PDF of each
    figure, in the order of ``names``).

    ``workers``: processes drawing the figures; None chooses (several on a machine with enough
    cores and figures, else serial), 1 draws serially in this process. Every path writes the
    same bytes."""
    run = data.load_run(run_dir)
    out_dir = Path(out_dir) if out_dir else Path(run_dir) / "figures"
    jobs: list[parallel.Job] = []
    for name in names:
        figs = _figure_jobs(run, name)
        if not figs:
            log(f"figure {name}: nothing to draw in this run (skipped)")
        jobs += [(name, make_figure, out_dir / stem) for stem, make_figure in figs]
    made: list[Path] = []
    for paths in parallel.draw(jobs, parallel.worker_count(len(jobs), workers)):
        made += paths
    log(f"{len(made) // 2} figure(s) in {out_dir}")
    return made


def draw_run_figures(result, *, log=print, workers: int | None = None) -> list[Path]:
    """The figures a finished run names (a ``study.RunResult``: its ``out_dir`` and
    ``figures``), drawn into RUN_DIR/figures; returns the written files."""
    t0 = time.perf_counter()
    made = render_figures(result.out_dir, result.figures, log=log, workers=workers)
    log(f"figures drawn in {time.perf_counter() - t0:.1f} s")
    return made
