"""Redraw every figure of a run directory from its stored results (no rendering)."""

from __future__ import annotations

from pathlib import Path

from jaxrender.figures import data, plots
from jaxrender.figures.io import save_figure
from jaxrender.study.schema import FIGURES


def _figures_for(run: data.Run, name: str):
    """(stem, Figure) pairs of one figure kind."""
    if name == "image_grid":
        return [(f"image_grid__{s}", plots.fig_image_grid(t))
                for s, t in data.image_grid_panels(run)]
    if name in ("pareto_time", "pareto_count"):
        x = "time_ms" if name == "pareto_time" else "shade_invocations"
        return [(f"{name}__{s}", plots.fig_pareto(data.pareto_table(run, s, x)))
                for s in data.scenes(run)]
    if name == "temporal":
        return [(f"temporal__{s}", plots.fig_temporal(t)) for s, t in data.temporal_tables(run)]
    if name == "dacs_decisions":
        return [(f"dacs_decisions__{s}", plots.fig_dacs_decisions(t))
                for s, t in data.aux_tables(run, "dacs")]
    if name == "object_space_marking":
        return [(f"object_space_marking__{s}", plots.fig_object_space_marking(t))
                for s, t in data.aux_tables(run, "object_space")]
    if name == "visbuffer_waves":
        return [(f"visbuffer_waves__{s}", plots.fig_visbuffer_waves(t))
                for s, t in data.waves_tables(run)]
    if name == "summary_table":
        return [("summary_table", plots.fig_summary_table(data.summary_table(run)))]
    raise ValueError(f"unknown figure {name!r}; known: {', '.join(FIGURES)}")


def render_figures(run_dir, names=FIGURES, *, out_dir=None, log=print) -> list[Path]:
    """Draw the named figures into ``out_dir`` (default RUN_DIR/figures); figures without
    data in this run are skipped with a note."""
    run = data.load_run(run_dir)
    out_dir = Path(out_dir) if out_dir else Path(run_dir) / "figures"
    made: list[Path] = []
    for name in names:
        figs = _figures_for(run, name)
        if not figs:
            log(f"figure {name}: nothing to draw in this run (skipped)")
        for stem, fig in figs:
            made += save_figure(fig, out_dir / stem)
    log(f"{len(made) // 2} figure(s) in {out_dir}")
    return made
