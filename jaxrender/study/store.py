"""The result store: ``results.jsonl``, one tidy row per (scene, camera path, pipeline,
parameters, frame), appended atomically; ``results.csv`` exported from it.

Atomic appends: the rows of a sequence are written as complete lines in one ``os.write`` on an
``O_APPEND`` descriptor, then fsync'd. A process killed mid-write can leave at most a trailing
partial line; loading ignores it, and opening the store for writing cuts it off first.

Resumability is by sequence (scene, path, pipeline variant): the temporal error needs every
frame of a sequence, so a sequence counts as done only when all its frame rows are stored
under its ``seq`` key, which hashes everything that determines the rows (resolution, reference,
scene, path and parameters). Rows of other keys stay in the file but are not exported.
"""

from __future__ import annotations

import csv
import fcntl
import hashlib
import io
import json
import math
import os
import warnings
from pathlib import Path

import numpy as np

CSV_COLUMNS = (
    "scene", "camera_path", "pipeline", "params", "frame",
    "rmse", "psnr", "mssim", "flip", "delta_e", "temporal_error",
    "shade_invocations", "helper_lanes", "covered_pixels", "shader_cost", "shading_work",
    "time_ms", "timed_outputs",
    "compile_ms", "pipeline_type", "width", "height", "finite", "device", "jax_version", "seq",
)


def json_number(v):
    """A count as a plain JSON number (None when it is not a scalar)."""
    a = np.asarray(v)
    if a.size != 1:
        return None
    x = a.reshape(()).item()
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, int):
        return int(x)
    return float(x)


def seq_key(*parts) -> str:
    """A short stable hash of JSON-able parts."""
    blob = json.dumps(parts, sort_keys=True, default=repr, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def read_rows(path) -> list[dict]:
    """Every complete row of a results.jsonl; a trailing partial line is ignored."""
    path = Path(path)
    if not path.exists():
        return []
    data = path.read_bytes()
    rows = []
    lines = data.split(b"\n")
    for i, line in enumerate(lines[:-1]):  # the last element is b"" or a partial line
        if not line.strip():
            continue
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            warnings.warn(f"{path}: line {i + 1} is not valid JSON and is ignored", stacklevel=2)
    return rows


def latest_rows(rows, seqs=None) -> list[dict]:
    """One row per (seq, frame), the last written winning; only ``seqs`` if given."""
    by_key: dict = {}
    for r in rows:
        if seqs is None or r.get("seq") in seqs:
            by_key[(r.get("seq"), r.get("frame"))] = r
    return list(by_key.values())


class ResultStore:
    """Append-only JSON Lines store. ``force=True`` starts it empty."""

    def __init__(self, path, *, force: bool = False):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if force and self.path.exists():
            self.path.unlink()
        self.dropped_bytes = self._cut_partial_line()
        self.rows = read_rows(self.path)
        self._frames: dict[str, set] = {}
        for r in self.rows:
            self._frames.setdefault(r.get("seq"), set()).add(r.get("frame"))

    def _cut_partial_line(self) -> int:
        if not self.path.exists():
            return 0
        data = self.path.read_bytes()
        if not data or data.endswith(b"\n"):
            return 0
        keep = data.rfind(b"\n") + 1
        with open(self.path, "r+b") as f:
            f.truncate(keep)
            f.flush()
            os.fsync(f.fileno())
        return len(data) - keep

    def complete(self, seq: str, frames: int) -> bool:
        return self._frames.get(seq, set()) >= set(range(frames))

    def append(self, rows: list[dict]) -> None:
        """Write complete lines in one write, then fsync; under an exclusive lock, so that the
        processes of a distributed run sharing the file never interleave their lines (a short
        write leaves the rest of the blob to a second write)."""
        blob = "".join(json.dumps(r, sort_keys=True) + "\n" for r in rows).encode()
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            view = memoryview(blob)
            while view:
                n = os.write(fd, view)
                view = view[n:]
            os.fsync(fd)
        finally:
            os.close(fd)
        for r in rows:
            self.rows.append(r)
            self._frames.setdefault(r.get("seq"), set()).add(r.get("frame"))


def _csv_value(v):
    if isinstance(v, (dict, list)):
        return json.dumps(v, sort_keys=True, separators=(",", ":"))
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    if v is None:
        return ""
    return v


def atomic_write_text(path, text: str) -> None:
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", newline="") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def export_csv(rows: list[dict], path) -> None:
    """results.csv: the fixed columns first, then every other key (extra counts) sorted."""
    extra = sorted({k for r in rows for k in r} - set(CSV_COLUMNS))
    cols = list(CSV_COLUMNS) + extra
    rows = sorted(rows, key=lambda r: (str(r.get("scene")), str(r.get("camera_path")),
                                       str(r.get("pipeline")), json.dumps(r.get("params"),
                                       sort_keys=True), r.get("frame", 0)))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow([_csv_value(r.get(c)) for c in cols])
    atomic_write_text(path, buf.getvalue())
