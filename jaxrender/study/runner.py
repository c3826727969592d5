"""Run a study: render every (scene, camera path, pipeline variant, frame), score it against
the cached reference, time it and append its rows; then export and summarise. Figures are
drawn afterwards from the output directory (``jaxrender.figures.draw_run_figures``).

The output directory holds ``results.jsonl`` (the store), ``results.csv``, ``study.toml`` (the
resolved config), ``environment.json`` (device, jax version, code version), ``summary.csv``,
``time_fits.csv`` when the study sweeps ``shader_cost`` (``time_series``) and ``images/``
(small npz files of a few frames for the figures); the figures go to ``figures/``.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from jaxrender import timing
from jaxrender.pipelines.program import PipelineOverflow, stack_cameras
from jaxrender.study import (backend, cache, compile_cache, executables, shader_cost, store,
                             summary, time_series)
from jaxrender.study.programs import (COMPILE_WORKERS, compile_all, compile_variant,
                                      program_key, rendered_path, variant_scene)
from jaxrender.study.references import reference_frames
from jaxrender.study.specs import Study, to_toml


@dataclass
class RunResult:
    """A finished run: what it computed, and what the figures step needs (``out_dir`` and
    the ``figures`` the study names)."""

    out_dir: Path
    rows: list
    computed: int  # sequences rendered in this run
    skipped: int  # sequences already complete in the store
    summary: list
    warnings: list = field(default_factory=list)
    figures: tuple = ()  # the names of the figures to draw
    time_fits: list = field(default_factory=list)  # time_series.Series of a shader_cost sweep


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", s).strip("-") or "x"


def _save_npz(path: Path, meta: dict, **arrays) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.npz")
    with open(tmp, "wb") as f:
        np.savez_compressed(f, meta=np.array(json.dumps(meta, sort_keys=True)), **arrays)
    tmp.replace(path)


def _small(a) -> np.ndarray:
    """Half floats and narrow integers: the figures need no more, and every saved frame of
    every sequence is kept."""
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
    scene = variant_scene(scene, variant)
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
        counts = {k: store.json_number(v[t]) for k, v in counts_t.items() if v.ndim == 1}
        counts = {k: v for k, v in counts.items() if v is not None}
        counts.update(_work_columns(scene, counts))
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
    motion = (backend.motion_field(scene, cams, w, h, start=warm)
              if backend.needs_motion(study.metrics) and len(cams) > 1 else None)
    seq_metrics, per_frame = backend.sequence_metrics(
        images, np.stack([np.asarray(r["image"], np.float32) for r in refs]), study.metrics,
        motion)
    for r, te in zip(rows, per_frame):
        r.update(seq_metrics)
        r["temporal_error_frame"] = te
    return rows


def _work_columns(scene, counts: dict) -> dict:
    """``shader_cost`` (the scene's, as the variant renders it) and ``shading_work`` (layer
    evaluations: shade_invocations x (1 + shader_cost)); none for a scene without effects."""
    cost = backend.shader_cost(scene)
    if cost is None:
        return {}
    out = {shader_cost.KEY: cost}
    if isinstance(counts.get("shade_invocations"), (int, float)):
        out[shader_cost.WORK] = shader_cost.shading_work(counts["shade_invocations"], cost)
    return out


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


# ------------------------------------------------------------------ the whole study


def run_study(study: Study, out_dir, *, force: bool = False, progress: bool = True,
              log=print) -> RunResult:
    """Render, time and score every sequence of ``study`` not already stored in ``out_dir``
    (``force``: recompute all), then export results.csv and summary.csv. Draws no figures."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    compile_cache.enable()
    env = timing.environment()
    _write_run_files(study, out_dir, env)
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
    if todo:
        _render_all(study, todo, st, env, out_dir, progress, log)
    rows = store.latest_rows(st.rows, seqs)
    store.export_csv(rows, out_dir / "results.csv")
    summ = summary.summarize(rows)
    summary.write_summary(summ, out_dir / "summary.csv")
    log(summary.format_summary(summ))
    fits = time_series.fit_series(rows)
    if fits:  # the study sweeps shader_cost
        time_series.write_csv(fits, out_dir / "time_fits.csv")
        log("time against shading work (time_fits.csv):\n" + time_series.format_fits(fits))
    else:  # none from an earlier run's sweep either
        (out_dir / "time_fits.csv").unlink(missing_ok=True)
    warns = summary.convergence_warnings(study, rows)
    for w in warns:
        log(f"warning: {w}")
    return RunResult(out_dir, rows, len(todo), skipped, summ, warns, study.figures, fits)


def _write_run_files(study: Study, out_dir: Path, env: dict) -> None:
    store.atomic_write_text(out_dir / "study.toml", to_toml(study))
    store.atomic_write_text(out_dir / "environment.json", json.dumps(
        {**env, "code_version": cache.code_version(), "study_file": study.file,
         "date": time.strftime("%Y-%m-%d %H:%M:%S")}, indent=2) + "\n")


def _render_all(study: Study, todo, st, env, out_dir: Path, progress: bool, log) -> None:
    """Compile everything, then render, time, score and store each sequence of ``todo``."""
    total = sum(p.frames for _, p, _ in todo)
    bar = tqdm(total=total, unit="frame", disable=not progress, dynamic_ncols=True)
    try:
        scenes, cams = {}, {}
        for spec, path, _ in todo:
            if spec.label not in scenes:
                scenes[spec.label] = backend.load_scene(spec.source, dict(spec.params))
            if (spec.label, path.name) not in cams:
                cams[spec.label, path.name] = backend.make_cameras(
                    scenes[spec.label], rendered_path(study, path), *study.resolution)
        bar.set_description("compiling; references")
        t0, before = time.perf_counter(), (compile_cache.counts(), executables.counts())
        compiled = compile_all(study, todo, scenes, cams)
        log(f"compiled or loaded {len(compiled)} program(s) with {COMPILE_WORKERS} worker(s) "
            f"and rendered the references in {time.perf_counter() - t0:.1f} s"
            f"{executables.describe(before[1])}{compile_cache.describe(before[0])}")
        t0 = time.perf_counter()
        for spec in study.scenes:
            for path in study.paths:
                variants = [v for s, p, v in todo if s is spec and p is path]
                if not variants:
                    continue
                scene, seq_cams = scenes[spec.label], cams[spec.label, path.name]
                refs = reference_frames(scene, spec, seq_cams[study.warmup_frames:],
                                        study.reference, study.resolution,
                                        first_frame=study.warmup_frames)
                for v in variants:
                    bar.set_description(f"{spec.label}/{path.name}: {v.label}")
                    progs = (compiled[program_key(spec, v, len(seq_cams))],
                             compiled.get(program_key(spec, v)))
                    st.append(run_sequence(study, scene, spec, path, seq_cams, v, refs, env,
                                           out_dir, progress=bar, compiled=progs))
    finally:
        bar.close()
    log(f"rendered, timed and scored {total} frame(s) in {time.perf_counter() - t0:.1f} s")
