"""Benchmark rows as markdown tables and JSON files."""

from __future__ import annotations

import json


def fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1e-2 or abs(v) >= 1e5 else f"{v:.3f}"
    return "" if v is None else str(v)


def print_table(rows, columns: list[str], file=None) -> None:
    """Rows (any iterable of dicts, printed as they come) as a markdown table."""
    print("| " + " | ".join(columns) + " |", file=file)
    print("|" + "|".join("---" for _ in columns) + "|", file=file)
    for r in rows:
        print("| " + " | ".join(fmt(r.get(c)) for c in columns) + " |", file=file, flush=True)


def dump(path, payload: dict) -> None:
    if path:
        with open(path, "w") as fh:
            json.dump(payload, fh, indent=1, default=str)
