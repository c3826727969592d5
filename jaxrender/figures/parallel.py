"""Draw independent figure jobs in parallel worker processes (or serially, in-process).

A job is ``(label, make_figure, stem)``: ``make_figure`` is a picklable zero-argument callable
(a ``functools.partial`` of a ``jaxrender.figures.plots`` function and its prepared table)
that returns a Figure, and ``save_figure`` writes it to ``stem.png`` / ``stem.pdf``. Workers
receive the prepared table itself, so they neither read the run directory nor import JAX;
figures are deterministic (``io.save_figure``), so both paths write the same bytes.

Workers are started with "spawn", never "fork": the parent may have JAX (and other) threads
running, which a forked child would inherit in an undefined state. A spawned child normally
re-imports the parent's main script first; the workers here need nothing from it, so they are
started without it (``jaxrender.spawning.main_hidden``): an unguarded script calling ``run_study`` must not have
each worker re-run the study.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from matplotlib.figure import Figure

from jaxrender.figures.io import save_figure
from jaxrender.spawning import main_hidden

Job = tuple[str, Callable[[], Figure], Path]

MAX_WORKERS = 8
# Below these, spawning workers (each imports matplotlib: about a second of CPU) costs more
# than it saves; the 2-core CI machine stays serial.
MIN_AUTO_WORKERS = 3
MIN_AUTO_JOBS = 6


def available_cpus() -> int:
    """CPUs this process may run on (its affinity mask, where the platform has one)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def worker_count(n_jobs: int, workers: int | None = None) -> int:
    """How many processes draw ``n_jobs`` figures; 1 means serially in this process.

    ``workers=None`` chooses: ``min(cpus, 8, n_jobs)``, or 1 when that is 2 or fewer or there
    are fewer than 6 jobs. An explicit ``workers`` is used as given (capped at ``n_jobs``)."""
    if workers is not None:
        if workers < 1:
            raise ValueError(f"workers must be >= 1 (or None for automatic), got {workers}")
        return max(1, min(workers, n_jobs))
    n = min(available_cpus(), MAX_WORKERS, n_jobs)
    return 1 if n < MIN_AUTO_WORKERS or n_jobs < MIN_AUTO_JOBS else n


def _draw(make_figure: Callable[[], Figure], stem: Path) -> list[Path]:
    return save_figure(make_figure(), stem)


def _note(err: BaseException, label: str, stem: Path, where: str) -> None:
    err.add_note(f"while drawing figure {label} ({Path(stem).name}){where}")


def draw(jobs: list[Job], workers: int = 1) -> list[list[Path]]:
    """Draw every job; the written paths of each job, in the order of ``jobs``.

    A failing job raises its own exception (in the parent, whichever path drew it) with a note
    naming the figure; the jobs not yet started are cancelled."""
    if workers <= 1 or len(jobs) <= 1:
        out = []
        for label, make_figure, stem in jobs:
            try:
                out.append(_draw(make_figure, stem))
            except Exception as e:
                _note(e, label, stem, "")
                raise
        return out
    ctx = multiprocessing.get_context("spawn")
    ex = ProcessPoolExecutor(max_workers=min(workers, len(jobs)), mp_context=ctx)
    try:
        with main_hidden():  # workers are spawned as jobs are submitted
            futures = [ex.submit(_draw, make_figure, stem) for _, make_figure, stem in jobs]
        out = []
        for (label, _, stem), fut in zip(jobs, futures):
            try:
                out.append(fut.result())
            except Exception as e:
                _note(e, label, stem, " in a worker process")
                raise
        return out
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
