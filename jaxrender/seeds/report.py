"""The sources' published numbers beside ours, in one table: ``jaxrender report``.

Each source in ``SOURCES`` is a module of this package with ``SOURCE`` (its name), ``STUDY``
(the bundled study whose run measures ours) and ``claims(rows, conditions) -> list[Claim]``
(``conditions``: a string saying where and how the run was made); a source may also offer
``TABLE_STEM``, ``table_rows(rows)`` and ``format_table(table)``: its own table in the paper's
layout, written beside its run. The report runs each source's study (resuming what a run
folder holds) or, with ``read_only``, reads the runs already there, collects the claims and
writes ``report.md`` and ``report.csv``: source, figure or slide, quantity, published value,
ours, our conditions, verdict (reproduced within the stated tolerance / direction reproduced /
not reproduced / not measured) and the reason.
"""

from __future__ import annotations

import csv
import importlib
import io
import json
import math
from pathlib import Path

from jaxrender.errors import UserError
from jaxrender.seeds.claim import Claim
from jaxrender.study import store
from jaxrender.study.runner import run_study
from jaxrender.study.schema import load_study

# The sources, in report order (the modules of this package named so).
SOURCES = ("jaxrender.seeds.dacs", "jaxrender.seeds.decima", "jaxrender.seeds.oxide")
COLUMNS = ("source", "figure", "quantity", "published", "ours", "conditions", "verdict",
           "reason")


def source_modules(names=None) -> list:
    """The source modules named in ``names`` (default: ``SOURCES``)."""
    return [importlib.import_module(n) for n in (SOURCES if names is None else names)]


def conditions_of(run_dir: Path) -> str:
    """Where and how a run was made, from its resolved study and environment files."""
    try:
        env = json.loads((run_dir / "environment.json").read_text())
        study = load_study(run_dir / "study.toml")
    except (OSError, ValueError, UserError) as e:
        raise UserError(f"{run_dir}: not a finished study run ({e})") from None
    w, h = study.resolution
    frames = "/".join(str(p.frames) for p in study.paths)
    return (f"{w}x{h}, {frames} frames, {env.get('device', '?')}, "
            f"{str(env.get('date', '?'))[:10]}")


def _rows_of(run_dir: Path) -> list[dict]:
    path = run_dir / "results.jsonl"
    if not path.is_file():
        raise UserError(f"{run_dir}: no results.jsonl; run the report without --read first")
    return store.latest_rows(store.read_rows(path))


def measure(source, runs: Path, *, read_only=False, resolution=None, frames=None,
            force=False, progress=True, log=print) -> tuple[list[dict], Path]:
    """(rows, run folder) of ``source``'s study: run into ``runs/<study name>`` (resuming),
    with the overrides, or read from there."""
    study = load_study(source.STUDY).with_overrides(frames=frames, resolution=resolution)
    run_dir = Path(runs) / study.name
    if read_only:
        return _rows_of(run_dir), run_dir
    log(f"{source.SOURCE}: study {study.name} -> {run_dir}")
    return run_study(study, run_dir, force=force, progress=progress, log=log).rows, run_dir


def write_source_table(source, rows: list[dict], run_dir: Path, log=print) -> Path | None:
    """The source's own table (if it has one) as Markdown and CSV in ``run_dir``, printed."""
    if not hasattr(source, "table_rows"):
        return None
    table = source.table_rows(rows)
    text = source.format_table(table)
    if hasattr(source, "table_notes"):
        text += "\n" + source.table_notes(rows) + "\n"
    md = Path(run_dir) / f"{source.TABLE_STEM}.md"
    store.atomic_write_text(md, f"# {source.SOURCE}\n\n{text}")
    store.atomic_write_text(md.with_suffix(".csv"), _csv(table, list(table[0]) if table else []))
    log(f"{source.SOURCE} ({md}):\n{text}")
    return md


def tables_for_study(study_name: str, rows: list[dict], run_dir: Path, log=print) -> list:
    """The tables of every source measured by ``study_name`` (``jaxrender study`` calls it)."""
    return [write_source_table(s, rows, run_dir, log) for s in source_modules()
            if s.STUDY == study_name]


def collect(runs: Path, *, sources=None, tables_to: Path | None = None, log=print,
            **how) -> list[Claim]:
    """Every source's claims, each from its study's run in ``runs`` (``how``: ``measure``'s
    options); a source's own table goes beside its run and, if given, into ``tables_to``."""
    out = []
    for src in sources if sources is not None else source_modules():
        rows, run_dir = measure(src, runs, log=log, **how)
        for folder in {Path(run_dir), *([Path(tables_to)] if tables_to else [])}:
            folder.mkdir(parents=True, exist_ok=True)
            write_source_table(src, rows, folder, log if folder == Path(run_dir) else _quiet)
        out += src.claims(rows, conditions_of(run_dir))
    return out


def _quiet(*_):
    pass


def _number(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "" if v is None else str(v)
    return f"{v:.4g}"


def format_markdown(claims: list[Claim]) -> str:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for c in claims:
        r = c.as_row()
        r["published"], r["ours"] = _number(r["published"]), _number(r["ours"])
        lines.append("| " + " | ".join(str(r[k]).replace("|", "/") for k in COLUMNS) + " |")
    return "\n".join(lines) + "\n"


def _csv(rows: list[dict], cols: list[str]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    w.writerows([[r.get(k) for k in cols] for r in rows])
    return buf.getvalue()


def write_report(claims: list[Claim], out: Path) -> tuple[Path, Path]:
    """report.md and report.csv in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    verdicts: dict = {}
    for c in claims:
        verdicts[c.verdict] = verdicts.get(c.verdict, 0) + 1
    tally = ", ".join(f"{n} {v}" for v, n in sorted(verdicts.items()))
    md = out / "report.md"
    store.atomic_write_text(md, "# The sources' published numbers beside ours\n\n"
                            f"{len(claims)} claims: {tally}.\n\n" + format_markdown(claims))
    rows = [c.as_row() for c in claims]
    store.atomic_write_text(out / "report.csv", _csv(rows, list(COLUMNS)))
    return md, out / "report.csv"
