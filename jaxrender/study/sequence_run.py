"""One sequence of a study: a scene, a camera path and a pipeline variant rendered as one
``render_sequence`` program, timed (that program or its images-only twin, and the
single-frame program: ``programs.roles``), scored frame by frame against the cached
references, with the saved frames' small npz files for the figures. ``runner`` runs the
whole study out of these.
"""

from __future__ import annotations

import json
import math
import os
import re
import threading
from pathlib import Path

import numpy as np

from jaxrender import timing
from jaxrender.pipelines.program import PipelineOverflow, stack_cameras
from jaxrender.study import backend, shader_cost, store
from jaxrender.study.programs import (SequencePrograms, compile_variant, compile_workers,
                                      sequence_programs, variant_scene)
from jaxrender.study.specs import Study


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", s).strip("-") or "x"


def _save_npz(path: Path, meta: dict, **arrays) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    # A name of this thread's own: the devices' threads may save one reference frame at once.
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp.npz")
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


def sequence_key(study: Study, spec, path, variant) -> str:
    """The rows' sequence key: everything a sequence's rows depend on (scene, path, variant,
    resolution, reference, metrics, warm-up frames, and what the timed program returns: a run
    resumed over rows timed otherwise computes them again rather than mix the two)."""
    ref = study.reference
    # Rows timed with the counts (the only way before [timing] outputs) keep their keys.
    timed = [] if study.timing.outputs == "all" else [study.timing.outputs]
    return store.seq_key(
        [spec.source, spec.params, spec.file_hash], [path.name, path.type, path.frames,
                                                     path.params],
        [variant.label, variant.type, variant.params_json], study.resolution,
        [ref.pipeline, ref.params], sorted(study.metrics), study.warmup_frames, *timed,
    )


def _render_timed(study: Study, progs: SequencePrograms, scene, cams_all, cams):
    """(frames of the instrumented sequence program, the timed sequence program's median ms,
    the single-frame program's median ms per scored frame, or NaN without one)."""
    reps, warm = study.timing.repeats, study.timing.warmup
    path = stack_cameras(cams_all)  # once, outside the timed calls
    if progs.timed is None:
        frames, seq_ms, _ = timing.time_call(progs.instrumented.call, scene, path,
                                             repeats=reps, warmup=warm)
    else:
        frames = timing.block(progs.instrumented.call(scene, path))
        _, seq_ms, _ = timing.time_call(progs.timed.call, scene, path, repeats=reps,
                                        warmup=warm)
    if progs.single is None:
        return frames, seq_ms, [float("nan")] * len(cams)
    for _ in range(warm):
        timing.block(progs.single.call(scene, cams[0]))
    single = [timing.time_call(progs.single.call, scene, cam, repeats=reps)[1] for cam in cams]
    return frames, seq_ms, single


def run_sequence(study: Study, scene, spec, path, cams_all, variant, refs, env, out_dir: Path,
                 progress=None, compiled: SequencePrograms | None = None, *,
                 seq: str | None = None, save_images: bool = True) -> list[dict]:
    """Render one sequence (``cams_all``: the rendered path, warm-up frames first) as one
    ``render_sequence`` program, time it (or, with ``timing.outputs = "images"``, its
    images-only twin) and its single-frame program, score every scored frame; returns its
    rows (not yet stored). ``compiled``: its programs (default: compiled here); ``seq``: the
    rows' sequence key (default: the variant's); ``save_images``: keep the ``save_frames``
    (a bisection's probes do not)."""
    w, h = study.resolution
    warm = study.warmup_frames
    cams = cams_all[warm:]
    scene = variant_scene(scene, variant)
    progs = compiled or sequence_programs(
        study, spec, variant, len(cams_all), lambda n, outputs: compile_variant(
            study, scene, cams_all if n else cams[0], variant, sequence=bool(n),
            outputs=outputs))
    try:
        frames, seq_ms, single_ms = _render_timed(study, progs, scene, cams_all, cams)
    except PipelineOverflow as e:
        raise PipelineOverflow(f"scene {spec.label!r}, path {path.name!r}, pipeline "
                               f"{variant.label!r} {variant.params_json}: {e}") from None
    seq = seq or sequence_key(study, spec, path, variant)
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
            # what was timed here: a count-matching probe times its instrumented program
            "timed_outputs": "all" if progs.timed is None else "images",
            "compile_ms": progs.instrumented.compile_ms,
            "compile_ms_timed": progs.timed.compile_ms if progs.timed else float("nan"),
            "compile_ms_single": progs.single.compile_ms if progs.single else float("nan"),
            "compile_method": progs.instrumented.method, "compile_workers": compile_workers(),
            "finite": finite, **env,
        }
        if "convergence_psnr" in refs[t]:
            row["reference_convergence_psnr"] = float(refs[t]["convergence_psnr"])
        rows.append(row)
        if save_images and t in study.save_frames:
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
