"""Run a study: render every (scene, camera path, pipeline variant, frame), score it against
the cached reference, time it and append its rows; then export, summarise and draw figures.

The output directory holds ``results.jsonl`` (the store), ``results.csv``, ``study.toml`` (the
resolved config), ``environment.json`` (device, jax version, code version), ``summary.csv``,
``images/`` (small npz files of a few frames for the figures) and ``figures/``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from jaxrender.pipelines.program import PipelineOverflow, stack_cameras
from jaxrender import timing
from jaxrender.study import backend, cache, schema, store
from jaxrender.study.schema import Study


@dataclass
class RunResult:
    out_dir: Path
    rows: list
    computed: int  # sequences rendered in this run
    skipped: int  # sequences already complete in the store
    summary: list
    warnings: list = field(default_factory=list)
    figures: list = field(default_factory=list)


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", s).strip("-") or "x"


def _scene_and_cameras(spec, path, resolution):
    scene = backend.load_scene(spec.source, dict(spec.params))
    return scene, backend.make_cameras(scene, path, *resolution)


def _py(v):
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


def reference_frames(scene, spec, cams, ref, resolution, programs: dict | None = None
                     ) -> list[dict]:
    """The reference frame of each camera, from the cache or rendered and cached. ``programs``
    (scene label -> compiled reference) lets a scene's camera paths share one compile."""
    programs = {} if programs is None else programs
    out, compiled = [], programs.get(spec.label)
    if hasattr(compiled, "result"):  # compiling in compile_all's pool
        compiled = programs[spec.label] = compiled.result()
    for cam in cams:
        key = cache.reference_key(spec, cam, ref, resolution)
        arrays = cache.load(key)
        if arrays is None:
            if compiled is None:
                compiled = programs[spec.label] = compile_reference(scene, cam, ref,
                                                                    resolution)
            frame = compiled.call(scene, cam)
            arrays = {"image": np.asarray(frame.image, np.float32)}
            conv = frame.counts.get("convergence_psnr") if frame.counts else None
            if conv is not None:
                arrays["convergence_psnr"] = np.float64(_py(conv))
            cache.save(key, arrays)
        out.append(arrays)
    return out


def compile_reference(scene, cam, ref, resolution) -> timing.Compiled:
    """The reference's single-frame program: references are rendered and cached per frame."""
    pipe = backend.pipeline(ref.pipeline)
    cfg = backend.make_config(ref.pipeline, *resolution, dict(ref.params))
    return timing.compile_program(pipe, scene, cam, cfg)


def hardest_crop(error: np.ndarray, size: int) -> tuple[int, int, int, int]:
    """(y0, x0, h, w) of the size x size window with the largest summed error."""
    h, w = error.shape
    s = max(1, min(size, h, w))
    ii = np.pad(np.cumsum(np.cumsum(error.astype(np.float64), 0), 1), ((1, 0), (1, 0)))
    sums = ii[s:, s:] - ii[:-s, s:] - ii[s:, :-s] + ii[:-s, :-s]
    y0, x0 = np.unravel_index(int(np.argmax(sums)), sums.shape)
    return int(y0), int(x0), s, s


def _save_npz(path: Path, meta: dict, **arrays) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.npz")
    with open(tmp, "wb") as f:
        np.savez_compressed(f, meta=np.array(json.dumps(meta, sort_keys=True)), **arrays)
    tmp.replace(path)


def _small(a) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.kind == "f":
        return a.astype(np.float16)
    if a.dtype.kind == "b":
        return a.astype(np.uint8)
    if a.dtype.kind in "iu" and a.size and a.min() >= -32768 and a.max() < 32768:
        return a.astype(np.int16)
    return a


def _seq(study: Study, spec, path, variant) -> str:
    ref = study.reference
    return store.seq_key(
        [spec.source, spec.params, spec.file_hash], [path.name, path.type, path.frames,
                                                     path.params],
        [variant.label, variant.type, variant.params_json], study.resolution,
        [ref.pipeline, ref.params], sorted(study.metrics), study.warmup_frames,
    )


# Programs compiled side by side before a scene's sequences are timed (never during timing).
# compile_ms is then the wall time of a compile that shared the machine with this many others;
# the rows carry the number as compile_workers.
COMPILE_WORKERS = max(1, min(8, os.cpu_count() or 1))


def rendered_path(study: Study, path):
    """The path as rendered: its frames plus the study's warm-up frames before them."""
    return dataclasses.replace(path, frames=path.frames + study.warmup_frames)


def compile_variant(study: Study, scene, cameras, variant, *, sequence: bool) -> timing.Compiled:
    """The variant's sequence program over ``cameras`` (the rendered path, warm-up included)
    or, with ``sequence=False``, its single-frame program (``cameras`` one camera)."""
    w, h = study.resolution
    pipe = backend.pipeline(variant.type)
    cfg = backend.make_config(variant.type, w, h, dict(variant.params))
    return timing.compile_program(pipe, scene, cameras, cfg, sequence=sequence,
                                  warmup_frames=study.warmup_frames if sequence else 0)


def program_key(spec, variant, frames: int = 0) -> tuple:
    """One compiled program per scene, variant and sequence length (0: the single-frame
    program): the points of a sweep share a label, so the key holds their parameters too."""
    return spec.label, variant.label, variant.params_json, frames


def compile_all(study: Study, todo, scenes: dict, cams: dict) -> dict:
    """Compile every program of ``todo`` (per scene and variant the sequence program of each
    path length and the single-frame program), and the reference program of each scene whose
    references are not all cached, side by side while this thread renders the references into
    the cache. ``cams[scene label, path name]`` are the rendered path's cameras (warm-up
    included). Returns {program_key: Compiled}; nothing is timed until every compile is done.

    With more than two workers (or ``JAXRENDER_COMPILE_PROCESSES=1``) the programs compile in
    spawned worker processes (``compile_pool``): tracing and lowering hold the GIL, so threads
    would take turns on it. Otherwise (and for any program a worker cannot take) in a thread
    pool: XLA compiles outside the GIL, so N cores still compile N programs at once."""
    from concurrent.futures import ThreadPoolExecutor

    from jaxrender.study import compile_pool

    pool = ThreadPoolExecutor(max_workers=COMPILE_WORKERS)
    procs = (compile_pool.ProcessCompiler(COMPILE_WORKERS, pool)
             if compile_pool.use_processes(COMPILE_WORKERS) else None)
    futures, programs = {}, {}
    pairs = {(s.label, p.name): (s, p) for s, p, _ in todo}
    warm = study.warmup_frames

    def submit(label, spec, path, pipe, params, sequence, fn, *args):
        """fn(*args) in a thread, or its program (pipeline ``pipe`` with ``params``) in a
        worker process with fn(*args) as the fallback."""
        if procs is None:
            return pool.submit(fn, *args)
        try:
            job = compile_pool.Job(
                backend.load_scene, backend.make_cameras, spec.source,
                tuple(dict(spec.params).items()), rendered_path(study, path),
                tuple(study.resolution), backend.pipeline(pipe),
                backend.make_config(pipe, *study.resolution, dict(params)),
                sequence=sequence, warmup_frames=warm if sequence else 0,
                scene=scenes[spec.label])
        except Exception:  # fn raises it again, where the thread path would
            return pool.submit(fn, *args)
        return procs.submit(label, job, lambda: fn(*args))

    try:
        # Submission order matters: tracing holds the GIL, so the longest chains start first.
        # References first (this thread renders them while the rest compiles), then programs
        # with host-side preparation (object-space charts), then the others.
        for spec, path in pairs.values():
            ref_cams = cams[spec.label, path.name][warm:]
            missing = not all(cache.has(cache.reference_key(spec, c, study.reference,
                                                            study.resolution)) for c in ref_cams)
            if missing and spec.label not in programs:
                ref = study.reference
                programs[spec.label] = submit(
                    f"the reference of {spec.label}", spec, path, ref.pipeline, ref.params,
                    False, compile_reference, scenes[spec.label], ref_cams[0], ref,
                    study.resolution)
        has_prep = lambda v: backend.pipeline(v.type).prepares  # noqa: E731
        for spec, path, v in sorted(todo, key=lambda t: not has_prep(t[2])):
            seq_cams = cams[spec.label, path.name]
            for frames in (len(seq_cams), 0) if study.timing.single_frame else (len(seq_cams),):
                key = program_key(spec, v, frames)
                if key not in futures:
                    what = f"{spec.label}/{v.label}" + (f" ({frames} frames)" if frames else "")
                    args = (seq_cams, v) if frames else (seq_cams[warm], v)
                    futures[key] = submit(what, spec, path, v.type, v.params, bool(frames),
                                          partial(compile_variant, sequence=bool(frames)),
                                          study, scenes[spec.label], *args)
        for spec, path in pairs.values():
            reference_frames(scenes[spec.label], spec, cams[spec.label, path.name][warm:],
                             study.reference, study.resolution, programs=programs)
        return {key: f.result() for key, f in futures.items()}
    finally:
        if procs is not None:
            procs.shutdown()
        pool.shutdown(wait=True, cancel_futures=True)


def _render_timed(study: Study, seq_prog, one_prog, scene, cams_all, cams):
    """(frames of the sequence, its median ms, single-frame median ms per scored frame or
    NaN without a single-frame program)."""
    reps, warm = study.timing.repeats, study.timing.warmup
    path = stack_cameras(cams_all)  # once, outside the timed calls
    frames, seq_ms, _ = timing.time_call(seq_prog.call, scene, path, repeats=reps, warmup=warm)
    if one_prog is None:
        return frames, seq_ms, [float("nan")] * len(cams)
    for _ in range(warm):
        timing.block(one_prog.call(scene, cams[0]))
    single = [timing.time_call(one_prog.call, scene, cam, repeats=reps)[1] for cam in cams]
    return frames, seq_ms, single


def run_sequence(study: Study, scene, spec, path, cams_all, variant, refs, env, out_dir: Path,
                 progress=None, compiled: tuple | None = None) -> list[dict]:
    """Render one sequence (``cams_all``: the rendered path, warm-up frames first) as one
    ``render_sequence`` program, time it and its single-frame program, score every scored
    frame; returns its rows (not yet stored). ``compiled``: (sequence, single) programs."""
    w, h = study.resolution
    warm = study.warmup_frames
    cams = cams_all[warm:]
    seq_prog, one_prog = compiled or (
        compile_variant(study, scene, cams_all, variant, sequence=True),
        compile_variant(study, scene, cams[0], variant, sequence=False)
        if study.timing.single_frame else None)
    try:
        frames, seq_ms, single_ms = _render_timed(study, seq_prog, one_prog, scene, cams_all,
                                                  cams)
    except PipelineOverflow as e:
        raise PipelineOverflow(f"scene {spec.label!r}, path {path.name!r}, pipeline "
                               f"{variant.label!r} {variant.params_json}: {e}") from None
    seq = _seq(study, spec, path, variant)
    images = np.asarray(frames.image, np.float32)
    counts_t = {k: np.asarray(v) for k, v in (frames.counts or {}).items()}
    rows = []
    for t in range(len(cams)):
        img = images[t]
        ref = np.asarray(refs[t]["image"], np.float32)
        if img.shape != ref.shape:
            raise ValueError(f"pipeline {variant.label!r} returned an image of shape "
                             f"{img.shape}, the reference is {ref.shape}")
        counts = {k: _py(v[t]) for k, v in counts_t.items() if v.ndim == 1}
        counts = {k: v for k, v in counts.items() if v is not None}
        finite = bool(np.all(np.isfinite(img))) and all(
            math.isfinite(v) for v in counts.values() if isinstance(v, float))
        metrics, err = backend.frame_metrics(img, ref, study.metrics)
        row = {
            "seq": seq, "scene": spec.label, "camera_path": path.name,
            "pipeline": variant.label, "pipeline_type": variant.type,
            "params": dict(variant.params), "frame": t, "width": w, "height": h,
            **metrics, **counts, "time_ms": seq_ms / len(cams_all),
            "time_ms_single": single_ms[t], "sequence_ms": seq_ms,
            "sequence_frames": len(cams_all), "warmup_frames": warm,
            "compile_ms": seq_prog.compile_ms,
            "compile_ms_single": one_prog.compile_ms if one_prog else float("nan"),
            "compile_method": seq_prog.method, "compile_workers": COMPILE_WORKERS,
            "finite": finite, **env,
        }
        if "convergence_psnr" in refs[t]:
            row["reference_convergence_psnr"] = float(refs[t]["convergence_psnr"])
        rows.append(row)
        if t in study.save_frames:
            aux = {k: np.asarray(v)[t] for k, v in (frames.aux or {}).items()}
            _save_frame_images(out_dir, spec, path, seq, t, row, img, err, ref, aux)
        if progress is not None:
            progress.update(1)
    seq_metrics, per_frame = backend.sequence_metrics(
        images, np.stack([np.asarray(r["image"], np.float32) for r in refs]), study.metrics)
    for r, te in zip(rows, per_frame):
        r.update(seq_metrics)
        r["temporal_error_frame"] = te
    return rows


def _save_frame_images(out_dir, spec, path, seq, t, row, img, err, ref, aux) -> None:
    meta = {k: row[k] for k in ("scene", "camera_path", "pipeline", "pipeline_type", "params",
                                 "frame", "seq")}
    aux = {f"aux_{k}": _small(v) for k, v in aux.items() if np.asarray(v).ndim >= 1}
    stem = f"{_slug(spec.label)}__{_slug(path.name)}__{seq}__f{t}"
    _save_npz(out_dir / "images" / f"{stem}.npz", meta, image=_small(img), error=_small(err),
              **aux)
    ref_stem = f"{_slug(spec.label)}__{_slug(path.name)}__reference__f{t}"
    if not (out_dir / "images" / f"{ref_stem}.npz").exists():
        _save_npz(out_dir / "images" / f"{ref_stem}.npz",
                  {"scene": spec.label, "camera_path": path.name, "pipeline": "reference",
                   "frame": t}, image=_small(ref))


# ------------------------------------------------------------------ summary


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


def _fmt(v: float, col: str) -> str:
    if isinstance(v, float) and math.isnan(v):
        return "-"
    if col == "shade_invocations":
        return f"{v:,.0f}"
    if col in ("mssim", "flip", "temporal_error"):
        return f"{v:.4f}"
    return f"{v:.2f}"


def convergence_warnings(study: Study, rows: list[dict]) -> list[str]:
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


# ------------------------------------------------------------------ the whole study


def run_study(study: Study, out_dir, *, force: bool = False, progress: bool = True,
              figures: bool = True, log=print) -> RunResult:
    from tqdm import tqdm

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    env = timing.environment()
    store.atomic_write_text(out_dir / "study.toml", schema.to_toml(study))
    store.atomic_write_text(out_dir / "environment.json", json.dumps(
        {**env, "code_version": cache.code_version(), "study_file": study.file,
         "date": time.strftime("%Y-%m-%d %H:%M:%S")}, indent=2) + "\n")
    st = store.ResultStore(out_dir / "results.jsonl", force=force)
    if st.dropped_bytes:
        log(f"note: cut off a partial last line ({st.dropped_bytes} bytes) from an interrupted run")

    plan = [(spec, path, v) for spec in study.scenes for path in study.paths
            for v in study.variants]
    seqs = {_seq(study, s, p, v) for s, p, v in plan}
    todo = [(s, p, v) for s, p, v in plan if not st.complete(_seq(study, s, p, v), p.frames)]
    skipped = len(plan) - len(todo)
    if skipped:
        log(f"{skipped} of {len(plan)} sequences already stored; computing {len(todo)}")
    total = sum(p.frames for _, p, _ in todo)
    bar = tqdm(total=total, unit="frame", disable=not progress or total == 0,
               dynamic_ncols=True)
    try:
        scenes, cams = {}, {}
        for spec, path, _ in todo:
            if spec.label not in scenes:
                scenes[spec.label] = backend.load_scene(spec.source, dict(spec.params))
            if (spec.label, path.name) not in cams:
                cams[spec.label, path.name] = backend.make_cameras(
                    scenes[spec.label], rendered_path(study, path), *study.resolution)
        bar.set_description("compiling; references")
        t0 = time.perf_counter()
        compiled = compile_all(study, todo, scenes, cams)
        if compiled:
            log(f"compiled {len(compiled)} program(s) with {COMPILE_WORKERS} worker(s) and "
                f"rendered the references in {time.perf_counter() - t0:.1f} s")
        t0 = time.perf_counter()
        for spec in study.scenes:
            for path in study.paths:
                variants = [v for s, p, v in todo if s is spec and p is path]
                if not variants:
                    continue
                scene, seq_cams = scenes[spec.label], cams[spec.label, path.name]
                refs = reference_frames(scene, spec, seq_cams[study.warmup_frames:],
                                        study.reference, study.resolution)
                for v in variants:
                    bar.set_description(f"{spec.label}/{path.name}: {v.label}")
                    progs = (compiled[program_key(spec, v, len(seq_cams))],
                             compiled.get(program_key(spec, v)))
                    rows = run_sequence(study, scene, spec, path, seq_cams, v, refs, env,
                                        out_dir, progress=bar, compiled=progs)
                    st.append(rows)
    finally:
        bar.close()
    if todo:
        log(f"rendered, timed and scored {total} frame(s) in {time.perf_counter() - t0:.1f} s")

    rows = store.latest_rows(st.rows, seqs)
    store.export_csv(rows, out_dir / "results.csv")
    summary = summarize(rows)
    _write_summary(summary, out_dir / "summary.csv")
    log(format_summary(summary))
    warns = convergence_warnings(study, rows)
    for w in warns:
        log(f"warning: {w}")
    made = []
    if figures:
        from jaxrender.figures.make import render_figures

        t0 = time.perf_counter()
        made = render_figures(out_dir, study.figures, log=log)
        log(f"figures drawn in {time.perf_counter() - t0:.1f} s")
    return RunResult(out_dir, rows, len(todo), skipped, summary, warns, made)


def _write_summary(summary: list[dict], path: Path) -> None:
    import csv
    import io

    cols = ["pipeline", "params", "rows", *SUMMARY_COLUMNS]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for e in summary:
        w.writerow([e[c] for c in cols])
    store.atomic_write_text(path, buf.getvalue())
