"""Figures: one pure function per figure (``plots``), one style file, deterministic saving."""

from jaxrender.figures.io import STYLE, save_figure  # noqa: F401
from jaxrender.figures.make import draw_run_figures, render_figures  # noqa: F401
from jaxrender.figures.plots import (  # noqa: F401
    fig_dacs_decisions,
    fig_image_grid,
    fig_object_space_marking,
    fig_pareto,
    fig_summary_table,
    fig_tads_samples,
    fig_temporal,
    fig_time_work,
    fig_visbuffer_waves,
)
