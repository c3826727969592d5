"""Read a run directory and prepare the plain tables the figure functions draw.

Aggregation (means over frames, Pareto fronts, the crop of the hardest region) happens here,
once; the figure functions only draw what they are given.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jaxrender.metrics import to_display
from jaxrender.study import store, time_series
from jaxrender.study.summary import SUMMARY_COLUMNS, summarize, timed_as

# aux names a pipeline may put in Frame.aux for the figures, in order of preference
DACS_LEVEL_KEYS = ("level", "dacs_level", "decision_level")
DACS_SHADED_KEYS = ("shaded", "shaded_mask", "decision")
OS_CHUNK_KEYS = ("chunk_state", "chunk_marking", "marking")
OS_MIP_KEYS = ("mip_level", "mip", "lod")
TADS_KEYS = ("sample_class", "duplicates")


@dataclass(frozen=True)
class Run:
    path: Path
    rows: list  # the current study's rows (results.jsonl, restricted to results.csv's seqs)
    images: list  # [(meta dict, npz path)]
    device: str


def _num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def load_run(run_dir) -> Run:
    run_dir = Path(run_dir)
    csv_path = run_dir / "results.csv"
    if not csv_path.exists():
        raise FileNotFoundError(f"{run_dir}: no results.csv (is this a study output directory?)")
    with open(csv_path, newline="") as f:
        seqs = {r["seq"] for r in csv.DictReader(f)}
    rows = store.latest_rows(store.read_rows(run_dir / "results.jsonl"), seqs)
    images = []
    for p in sorted((run_dir / "images").glob("*.npz")):
        with np.load(p) as z:
            meta = json.loads(str(z["meta"]))
        if meta.get("pipeline") == "reference" or meta.get("seq") in seqs:
            images.append((meta, p))
    device = ""
    env = run_dir / "environment.json"
    if env.exists():
        e = json.loads(env.read_text())
        device = f"{e.get('device', '')}, jax {e.get('jax_version', '')}"
    return Run(run_dir, rows, images, device)


def _arrays(p: Path) -> dict:
    with np.load(p) as z:
        return {k: z[k] for k in z.files if k != "meta"}


def variant_name(label: str, params) -> str:
    if isinstance(params, str):
        params = json.loads(params)
    if not params:
        return label
    return label + " " + ",".join(f"{k}={v}" for k, v in sorted(params.items()))


def _param_order(params: dict):
    return tuple((k, (0, v, "") if _num(v) else (1, 0, str(v))) for k, v in sorted(params.items()))


def _mean(rows, col) -> float:
    vals = [r[col] for r in rows if _num(r.get(col)) and not math.isnan(r[col])]
    return float(np.mean(vals)) if vals else float("nan")


def scenes(run: Run) -> list[str]:
    return sorted({r["scene"] for r in run.rows})


def pareto_front(points) -> list[tuple[float, float]]:
    """Points (cost x, quality y) not beaten by a cheaper-or-equal, better one."""
    pts = sorted((x, -y) for x, y in points if math.isfinite(x) and not math.isnan(y))
    front, best = [], -math.inf
    for x, ny in pts:
        if -ny > best:
            front.append((x, -ny))
            best = -ny
    return front


def time_label(rows) -> str:
    """The time axis's label, with what the timed programs returned (the rows'
    ``timed_outputs``; rows from before it are timed with their counts)."""
    what = {"images": ", images only", "all": ", counts included"}.get(timed_as(rows), "")
    return f"time per frame (ms, median{what})"


def pareto_table(run: Run, scene: str, x: str) -> dict:
    rows = [r for r in run.rows if r["scene"] == scene]
    by_label: dict = {}
    for r in rows:
        key = json.dumps(r["params"], sort_keys=True)
        by_label.setdefault(r["pipeline"], {}).setdefault(key, []).append(r)
    series, points = [], []
    for label in sorted(by_label):
        variants = sorted(by_label[label].items(), key=lambda kv: _param_order(json.loads(kv[0])))
        xs = [_mean(rs, x) for _, rs in variants]
        ys = [_mean(rs, "psnr") for _, rs in variants]
        series.append({"label": label, "x": xs, "y": ys})
        points += list(zip(xs, ys))
    finite_x = [p[0] for p in points if math.isfinite(p[0]) and p[0] > 0]
    logx = bool(finite_x) and max(finite_x) / min(finite_x) > 20
    xlabel = {"time_ms": time_label(rows),
              "shade_invocations": "shader invocations per frame"}.get(x, x)
    return {"title": f"{scene}: PSNR vs {xlabel.split(' (')[0]}", "xlabel": xlabel,
            "ylabel": "PSNR (dB)", "logx": logx, "device": run.device, "series": series,
            "front": pareto_front(points)}


def temporal_tables(run: Run) -> list[tuple[str, dict]]:
    out = []
    groups: dict = {}
    for r in run.rows:
        groups.setdefault((r["scene"], r["camera_path"]), []).append(r)
    for (scene, path), rows in sorted(groups.items()):
        if max(r["frame"] for r in rows) < 1:
            continue
        seqs: dict = {}
        for r in rows:
            seqs.setdefault((r["pipeline"], json.dumps(r["params"], sort_keys=True)), []).append(r)
        series = []
        for (label, params), rs in sorted(seqs.items()):
            rs = sorted(rs, key=lambda r: r["frame"])
            series.append({
                "label": variant_name(label, params),
                "frames": [r["frame"] for r in rs],
                "temporal": [r.get("temporal_error_frame", float("nan")) for r in rs],
                "psnr": [r.get("psnr", float("nan")) for r in rs],
            })
        out.append((f"{scene}__{path}", {"title": f"{scene} / {path}: temporal error",
                                         "device": run.device, "series": series}))
    return out


def image_grid_panels(run: Run, max_entries: int = 8) -> list[tuple[str, dict]]:
    refs = {(m["scene"], m["camera_path"], m["frame"]): p for m, p in run.images
            if m.get("pipeline") == "reference"}
    psnr = {(r["seq"], r["frame"]): r.get("psnr") for r in run.rows}
    out = []
    for key in sorted(refs):
        scene, path, frame = key
        if frame != min(f for s, c, f in refs if (s, c) == (scene, path)):
            continue
        ents = [(m, p) for m, p in run.images
                if m.get("pipeline") != "reference" and (m["scene"], m["camera_path"],
                                                         m["frame"]) == key]
        if not ents:
            continue
        ents.sort(key=lambda e: (e[0]["pipeline"], _param_order(e[0]["params"])))
        if len(ents) > max_entries:  # keep each pipeline entry's best variant
            best: dict = {}
            for m, p in ents:
                q = psnr.get((m["seq"], frame)) or -math.inf
                if m["pipeline"] not in best or q > best[m["pipeline"]][0]:
                    best[m["pipeline"]] = (q, m, p)
            ents = [(m, p) for _, m, p in best.values()][:max_entries]
        ref = display_image(_arrays(refs[key])["image"])
        entries, errs = [], []
        for m, p in ents:
            a = _arrays(p)
            err = a["error"].astype(np.float32)
            errs.append(err)
            q = psnr.get((m["seq"], frame))
            entries.append({"label": variant_name(m["pipeline"], m["params"]),
                            "image": display_image(a["image"]), "error": err,
                            "caption": f"PSNR {q:.2f} dB" if _num(q) else ""})
        total = np.sum(errs, axis=0)
        h, w = total.shape
        crop = hardest_crop(total, max(8, min(h, w) // 4))
        emax = float(max(np.percentile(e, 99.5) for e in errs)) or 1.0
        out.append((f"{scene}__{path}", {
            "title": f"{scene} / {path}, frame {frame}", "device": run.device,
            "reference": ref, "crop": crop, "error_max": emax, "entries": entries}))
    return out


def display_image(linear) -> np.ndarray:
    """A saved linear frame as shown: the metrics' ``to_display`` (clamp, sRGB encode), with
    NaN drawn black so that a broken frame still shows where it broke."""
    return np.asarray(to_display(np.nan_to_num(np.asarray(linear, np.float32), nan=0.0)))


def hardest_crop(error: np.ndarray, size: int) -> tuple[int, int, int, int]:
    """(y0, x0, h, w) of the size x size window with the largest summed error."""
    h, w = error.shape
    s = max(1, min(size, h, w))
    ii = np.pad(np.cumsum(np.cumsum(error.astype(np.float64), 0), 1), ((1, 0), (1, 0)))
    sums = ii[s:, s:] - ii[:-s, s:] - ii[s:, :-s] + ii[:-s, :-s]
    y0, x0 = np.unravel_index(int(np.argmax(sums)), sums.shape)
    return int(y0), int(x0), s, s


def _first(arrays: dict, keys):
    for k in keys:
        if f"aux_{k}" in arrays:
            return arrays[f"aux_{k}"]
    return None


def aux_tables(run: Run, kind: str, max_entries: int = 6) -> list[tuple[str, dict]]:
    """Per (scene, camera path), the first saved frame of every sequence whose Frame.aux holds
    the maps of ``kind``: "dacs" (a decision level and/or a shaded mask), "object_space"
    (chunk marking, optionally MIP levels) or "tads" (sample classes and duplicates)."""
    groups: dict = {}
    for m, p in run.images:
        if m.get("pipeline") == "reference":
            continue
        groups.setdefault((m["scene"], m["camera_path"]), {}).setdefault(m["seq"], (m, p))
    out = []
    for (scene, path), seqs in sorted(groups.items()):
        entries = []
        for m, p in sorted(seqs.values(), key=lambda e: (e[0]["pipeline"],
                                                         _param_order(e[0]["params"]))):
            a = _arrays(p)
            e = {"label": variant_name(m["pipeline"], m["params"]),
                 "image": display_image(a["image"])}
            if kind == "dacs":
                e["level"], e["shaded"] = _first(a, DACS_LEVEL_KEYS), _first(a, DACS_SHADED_KEYS)
                if e["level"] is None and e["shaded"] is None:
                    continue
            elif kind == "tads":
                e["sample_class"], e["duplicates"] = (_first(a, (k,)) for k in TADS_KEYS)
                if e["sample_class"] is None:
                    continue
            else:
                e["chunk_state"], e["mip_level"] = _first(a, OS_CHUNK_KEYS), _first(a, OS_MIP_KEYS)
                if e["chunk_state"] is None:
                    continue
            entries.append(e)
        if entries:
            what = {"dacs": "shading decisions", "tads": "TADS unique samples"}.get(
                kind, "object-space chunk marking")
            out.append((f"{scene}__{path}", {"title": f"{scene} / {path}: {what}",
                                             "device": run.device,
                                             "entries": entries[:max_entries]}))
    return out


def waves_tables(run: Run) -> list[tuple[str, dict]]:
    out = []
    for scene in scenes(run):
        rows = [r for r in run.rows if r["scene"] == scene and _num(r.get("waves"))
                and _num(r.get("lane_utilization"))]
        groups: dict = {}
        for r in rows:
            groups.setdefault((r["pipeline"], json.dumps(r["params"], sort_keys=True)),
                              []).append(r)
        if not groups:
            continue
        keys = sorted(groups, key=lambda k: (k[0], _param_order(json.loads(k[1]))))
        out.append((scene, {
            "title": f"{scene}: shading waves and lane utilisation", "device": run.device,
            "labels": [variant_name(*k) for k in keys],
            "waves": [_mean(groups[k], "waves") for k in keys],
            "utilization": [_mean(groups[k], "lane_utilization") for k in keys]}))
    return out


def summary_table(run: Run) -> dict:
    summ = summarize(run.rows)
    return {"title": "summary (mean over scenes, paths and frames)", "device": run.device,
            "columns": ["pipeline", "PSNR", "MSSIM", "FLIP", "temporal", "invocations",
                        "time ms"],
            "rows": [[variant_name(e["pipeline"], e["params"])]
                     + [e[c] for c in SUMMARY_COLUMNS] for e in summ]}


def time_work_tables(run: Run) -> list[tuple[str, dict]]:
    """Per (scene, camera path) of a shader_cost sweep: each pipeline variant's (shading work,
    time) points, its fitted line sampled over its range, and the point on it where it
    becomes faster than deferred (``study.time_series``)."""
    groups: dict = {}
    for s in time_series.fit_series(run.rows):
        groups.setdefault((s.scene, s.camera_path), []).append(s)
    out = []
    for (scene, path), series in sorted(groups.items()):
        entries, crossings = [], []
        for s in series:
            label = variant_name(s.pipeline, s.params)
            lo, hi = min(s.work), max(s.work)
            line_x = np.geomspace(lo, hi, 32) if lo > 0 else np.linspace(lo, hi, 32)
            entries.append({"label": label, "work": [w / 1e6 for w in s.work],
                            "time": list(s.time_ms), "line_work": list(line_x / 1e6),
                            "line_time": list(s.fit.predict(line_x)), "linear": s.fit.linear})
            c = s.crossover
            # A crossover beyond the sweep is an extrapolation (time_fits.csv says so); drawn,
            # it would stretch the axes over costs nobody measured.
            if c is not None and c.cost is not None and 0 < c.cost <= max(s.costs):
                w = s.invocations * (1 + c.cost)
                crossings.append({"label": label, "cost": c.cost, "work": w / 1e6,
                                  "time": float(s.fit.predict(w))})
        all_work = [w for e in entries for w in e["work"] if w > 0]
        out.append((f"{scene}__{path}", {
            "title": f"{scene} / {path}: time against shading work", "device": run.device,
            "xlabel": "shading work per frame (M layer evaluations: invocations x (1 + cost))",
            "ylabel": time_label([r for r in run.rows if r["scene"] == scene
                                  and r["camera_path"] == path]),
            "baseline": time_series.BASELINE,
            "log": bool(all_work) and max(all_work) / min(all_work) > 20,
            "series": entries, "crossings": crossings}))
    return out
