"""The summary of a study's rows: one line per pipeline variant (means over scenes, paths
and frames), printed after a run, written as summary.csv and drawn as the summary table."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np

from jaxrender.study import store


SUMMARY_COLUMNS = ("psnr", "mssim", "flip", "temporal_error", "shade_invocations", "time_ms")


def summarize(rows: list[dict]) -> list[dict]:
    """Mean over scenes, paths and frames per (pipeline label, parameters)."""
    groups: dict = {}
    for r in rows:
        key = (r["pipeline"], json.dumps(r.get("params", {}), sort_keys=True))
        groups.setdefault(key, []).append(r)
    def order(key):  # numbers in numeric order, so levels=2 comes before levels=16
        return key[0], [(k, (0, v, "") if isinstance(v, (int, float)) else (1, 0, str(v)))
                        for k, v in sorted(json.loads(key[1]).items())]

    out = []
    for (label, params), rs in sorted(groups.items(), key=lambda kv: order(kv[0])):
        entry = {"pipeline": label, "params": params, "rows": len(rs)}
        for c in SUMMARY_COLUMNS:
            vals = [r[c] for r in rs if isinstance(r.get(c), (int, float))
                    and not isinstance(r.get(c), bool) and not math.isnan(r[c])]
            entry[c] = float(np.mean(vals)) if vals else float("nan")
        out.append(entry)
    return out


def format_summary(summary: list[dict]) -> str:
    heads = ["pipeline", "PSNR", "MSSIM", "FLIP", "temporal", "invocations", "time ms"]
    lines = []
    for e in summary:
        name = e["pipeline"] + ("" if e["params"] == "{}" else " " + e["params"])
        lines.append([name] + [_fmt(e[c], c) for c in SUMMARY_COLUMNS])
    widths = [max(len(x) for x in col) for col in zip(heads, *lines)]
    fmt = lambda cells: "  ".join(  # noqa: E731
        c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths)))
    return "\n".join([fmt(heads), fmt(["-" * w for w in widths])] + [fmt(r) for r in lines])


def timed_as(rows) -> str | None:
    """What every row's ``time_ms`` timed: "images", "all" (rows stored before
    ``timed_outputs`` existed were timed with their counts), or None for no rows or a mix."""
    kinds = {r.get("timed_outputs", "all") for r in rows}
    return kinds.pop() if len(kinds) == 1 else None


TIME_NOTES = {
    "images": "time ms: per frame, timed with the images alone (counts from a second program)",
    "all": 'time ms: per frame, the counts and views timed too ([timing] outputs = "all")',
    None: "time ms: some rows timed the images alone, others with the counts and views",
}


def time_note(rows: list[dict]) -> str:
    """What the rows' ``time_ms`` measured, by their ``timed_outputs`` ([timing] outputs)."""
    return TIME_NOTES[timed_as(rows)] if rows else ""


def _fmt(v: float, col: str) -> str:
    if isinstance(v, float) and math.isnan(v):
        return "-"
    if col == "shade_invocations":
        return f"{v:,.0f}"
    if col in ("mssim", "flip", "temporal_error"):
        return f"{v:.4f}"
    return f"{v:.2f}"


def convergence_warnings(study, rows: list[dict]) -> list[str]:
    """A warning per scene whose reference is not min_margin_db above its best pipeline."""
    if not study.reference.check_convergence:
        return []
    out = []
    for spec in study.scenes:
        rs = [r for r in rows if r["scene"] == spec.label]
        conv = [r["reference_convergence_psnr"] for r in rs if "reference_convergence_psnr" in r]
        psnr: dict = {}
        for r in rs:
            if isinstance(r.get("psnr"), float):
                psnr.setdefault((r["pipeline"], json.dumps(r["params"], sort_keys=True)),
                                []).append(r["psnr"])
        if not conv or not psnr:
            continue
        best = max(float(np.mean(v)) for v in psnr.values())
        if min(conv) < best + study.reference.min_margin_db:
            out.append(f"reference for scene {spec.label!r} may not be converged: its "
                       f"convergence estimate is {min(conv):.1f} dB, the best pipeline reaches "
                       f"{best:.1f} dB (want a margin of {study.reference.min_margin_db:g} dB); "
                       "raise the reference's sample count")
    return out


def write_summary(summary: list[dict], path: Path) -> None:
    cols = ["pipeline", "params", "rows", *SUMMARY_COLUMNS]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for e in summary:
        w.writerow([e[c] for c in cols])
    store.atomic_write_text(path, buf.getvalue())
