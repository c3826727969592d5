"""Figure creation in the one style, and deterministic saving (PNG + PDF)."""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path

import matplotlib
import matplotlib.style
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

STYLE = str(Path(__file__).with_name("jaxrender.mplstyle"))


@contextlib.contextmanager
def style():
    with matplotlib.style.context(STYLE), matplotlib.rc_context({"svg.hashsalt": "jaxrender"}):
        yield


def new_figure(width_in: float, height_in: float) -> Figure:
    """A figure outside pyplot's global state, with an Agg canvas."""
    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, stem) -> list[Path]:
    """Write ``stem.png`` and ``stem.pdf``; equal figures give equal bytes (no dates, no
    software version in the metadata, a fixed hash salt)."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    png, pdf = stem.with_suffix(".png"), stem.with_suffix(".pdf")
    # PDFs use the 14 standard fonts (no embedding: fast, small, deterministic); matplotlib
    # logs each weight substitution for them, which says nothing useful here.
    fm_log = logging.getLogger("matplotlib.font_manager")
    level = fm_log.level
    fm_log.setLevel(logging.ERROR)
    try:
        _save(fig, png, pdf)
    finally:
        fm_log.setLevel(level)
    return [png, pdf]


def _save(fig: Figure, png: Path, pdf: Path) -> None:
    with style():
        fig.savefig(png, format="png", metadata={"Software": None})
        fig.savefig(pdf, format="pdf", metadata={"CreationDate": None, "ModDate": None,
                                                  "Producer": None, "Creator": None})

