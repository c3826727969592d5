"""Run a study: render every (scene, camera path, pipeline variant, frame), score it against
the cached reference, time it and append its rows; then export and summarise. Figures are
drawn afterwards from the output directory (``jaxrender.figures.draw_run_figures``); each
sequence is rendered, timed and scored by ``sequence_run``.

The output directory holds ``results.jsonl`` (the store), ``results.csv``, ``study.toml`` (the
resolved config), ``environment.json`` (device, jax version, code version), ``summary.csv``,
``time_fits.csv`` when the study sweeps ``shader_cost`` (``time_series``) and ``images/``
(small npz files of a few frames for the figures); the figures go to ``figures/``.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import jax
from tqdm import tqdm

from jaxrender import memory_maps, timing
from jaxrender.errors import StudyError
from jaxrender.study import (backend, cache, compile_cache, executables, matching,
                             program_batches, store, summary, time_series)
from jaxrender.study import devices as devices_mod
from jaxrender.study.programs import (compile_all, compile_variant, compile_workers,
                                      program_identity, program_key, rendered_path,
                                      retargeted, roles, sequence_programs, variant_scene)
from jaxrender.study.references import reference_frames
from jaxrender.study.sequence_run import run_sequence, sequence_key
from jaxrender.study.specs import Study, Variant, to_toml


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



# ------------------------------------------------------------------ the whole study


def run_study(study: Study, out_dir, *, force: bool = False, progress: bool = True,
              log=print, devices: int | None = None) -> RunResult:
    """Render, time and score every sequence of ``study`` not already stored in ``out_dir``
    (``force``: recompute all), then export results.csv and summary.csv. Draws no figures.
    The sequences spread over ``devices`` local devices (None: all of them) and, under JAX's
    distributed runtime, over the processes, which share ``out_dir`` (``study.devices``);
    the first process exports once every process has stored its rows."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    compile_cache.enable()
    env = timing.environment()
    first = jax.process_index() == 0
    if first:
        _write_run_files(study, out_dir, env)
    st = _open_store(out_dir, force)
    if st.dropped_bytes:
        log(f"note: cut off a partial last line ({st.dropped_bytes} bytes) from an interrupted run")
    plan = [(spec, path, v) for spec in study.scenes for path in study.paths
            for v in study.variants]
    seqs = {sequence_key(study, s, p, v) for s, p, v in plan}
    todo = [(s, p, v) for s, p, v in plan
            if not st.complete(sequence_key(study, s, p, v), p.frames)]
    skipped = len(plan) - len(todo)
    if skipped:
        log(f"{skipped} of {len(plan)} sequences already stored; computing {len(todo)}")
    computed, compiled = (_render_all(study, todo, st, env, out_dir, progress, log, devices)
                          if todo else (0, {}))
    if jax.process_count() > 1:  # every process's rows are in the file: read them all
        devices_mod.wait_for_all_processes("stored")
        st = store.ResultStore(out_dir / "results.jsonl")
        if not first:
            return RunResult(out_dir, store.latest_rows(st.rows, seqs), computed, skipped, [])
    # Matches bisect against every process's rows: the first process runs them.
    seqs |= _run_matches(study, st, env, out_dir, compiled, log)
    rows = store.latest_rows(st.rows, seqs)
    store.export_csv(rows, out_dir / "results.csv")
    summ = summary.summarize(rows)
    summary.write_summary(summ, out_dir / "summary.csv")
    note = summary.time_note(rows)
    log(summary.format_summary(summ) + (f"\n{note}" if note else ""))
    fits = time_series.fit_series(rows)
    if fits:  # the study sweeps shader_cost
        time_series.write_csv(fits, out_dir / "time_fits.csv")
        log("time against shading work (time_fits.csv):\n" + time_series.format_fits(fits))
    else:  # none from an earlier run's sweep either
        (out_dir / "time_fits.csv").unlink(missing_ok=True)
    warns = summary.convergence_warnings(study, rows)
    for w in warns:
        log(f"warning: {w}")
    return RunResult(out_dir, rows, computed, skipped, summ, warns, study.figures, fits)


def _open_store(out_dir: Path, force: bool) -> store.ResultStore:
    """The run's store; with several processes the first one discards old rows (``force``)
    before any other opens it."""
    path = out_dir / "results.jsonl"
    if jax.process_count() == 1:
        return store.ResultStore(path, force=force)
    st = store.ResultStore(path, force=force) if jax.process_index() == 0 else None
    devices_mod.wait_for_all_processes("store open")
    return st or store.ResultStore(path)


def _write_run_files(study: Study, out_dir: Path, env: dict) -> None:
    store.atomic_write_text(out_dir / "study.toml", to_toml(study))
    store.atomic_write_text(out_dir / "environment.json", json.dumps(
        {**env, "code_version": cache.code_version(), "study_file": study.file,
         "date": time.strftime("%Y-%m-%d %H:%M:%S")}, indent=2) + "\n")


def group_of(spec, variant) -> tuple:
    """The unit of placement: a scene and a program (all paths of a variant, and the sweep
    points that differ only in traced values, share its programs)."""
    return program_identity(spec, variant)[:3]


def _placement(study: Study, todo, devices) -> devices_mod.Placement:
    groups: dict = {}
    for spec, path, v in todo:
        g = group_of(spec, v)
        groups[g] = groups.get(g, 0) + path.frames + study.warmup_frames
    return devices_mod.place(groups, devices_mod.select_devices(devices))


def _render_all(study: Study, todo, st, env, out_dir: Path, progress: bool, log,
                devices: int | None = None) -> tuple[int, dict]:
    """Compile, then render, time, score and store each sequence of ``todo`` that this
    process renders (``devices``: how many local devices; None: all), a batch of sequences at
    a time where the process cannot hold every program at once (``program_batches``); returns
    how many it rendered and the last batch's compiled programs by ``program_key``."""
    placement = _placement(study, todo, devices)
    todo = [t for t in todo if placement.device_of(group_of(t[0], t[2])) is not None]
    total = sum(p.frames for _, p, _ in todo)
    bar = tqdm(total=total, unit="frame", disable=not progress, dynamic_ncols=True)
    compiled: dict = {}
    render_s = 0.0
    try:
        scenes, cams = _scenes_and_cameras(study, todo)
        most = program_batches.programs_at_once()
        parts = program_batches.batches(todo, partial(_programs_of, study, cams), most)
        if len(parts) > 1:
            log(f"the CPU backend holds at most {most} compiled programs at once: "
                f"{len(parts)} batches of sequences, each compiled, rendered and freed in turn")
        for i, part in enumerate(parts):
            if i:
                compiled = {}
                memory_maps.release()
            compiled = _compile_part(study, part, scenes, cams, placement, bar, log)
            if i == 0:
                bar.reset(total=total)  # the rate and ETA are the rendering's, not the compiles'
            t0 = time.perf_counter()
            _render_placed(study, part, st, env, out_dir, bar, compiled, scenes, cams, placement)
            render_s += time.perf_counter() - t0
    finally:
        bar.close()
    log(f"rendered, timed and scored {total} frame(s) in {render_s:.1f} s")
    return len(todo), compiled


def _scenes_and_cameras(study: Study, todo) -> tuple[dict, dict]:
    """Each scene of ``todo`` loaded once, and each (scene, path)'s rendered cameras."""
    scenes, cams = {}, {}
    for spec, path, _ in todo:
        if spec.label not in scenes:
            scenes[spec.label] = backend.load_scene(spec.source, dict(spec.params))
        if (spec.label, path.name) not in cams:
            cams[spec.label, path.name] = backend.make_cameras(
                scenes[spec.label], rendered_path(study, path), *study.resolution)
    return scenes, cams


def _programs_of(study: Study, cams: dict, item) -> set:
    """The identities of the programs a sequence runs (``programs.roles``)."""
    spec, path, v = item
    n = len(cams[spec.label, path.name])
    return {program_identity(spec, v, *fo) for fo in roles(study, n).values()}


def _compile_part(study: Study, part, scenes, cams, placement, bar, log) -> dict:
    """Every program of the sequences ``part`` (and their missing references), logged."""
    bar.set_description("compiling; references")
    t0, before = time.perf_counter(), (compile_cache.counts(), executables.counts())
    where = {g: placement.devices[d] for g, d in placement.group_device.items()}
    compiled = compile_all(study, part, scenes, cams,
                           device_of=lambda spec, v: where[group_of(spec, v)])
    on = (f" for {len(placement.devices)} device(s)" if len(placement.devices) > 1 else "")
    log(f"compiled or loaded {len(compiled)} program(s){on} with {compile_workers()} "
        f"worker(s) and rendered the references in {time.perf_counter() - t0:.1f} s"
        f"{executables.describe(before[1])}{compile_cache.describe(before[0])}")
    return compiled


def _render_placed(study, todo, st, env, out_dir, bar, compiled, scenes, cams, placement):
    """Each sequence on its group's device, one thread per device when there are several;
    rows are stored here, a sequence's together, as each finishes."""
    n = len(placement.devices)
    on_device: dict = {}  # (scene label, device index) -> the scene's arrays there
    jobs = []
    for spec in study.scenes:
        for path in study.paths:
            variants = [v for s, p, v in todo if s is spec and p is path]
            if not variants:
                continue
            seq_cams = cams[spec.label, path.name]
            refs = reference_frames(scenes[spec.label], spec, seq_cams[study.warmup_frames:],
                                    study.reference, study.resolution,
                                    first_frame=study.warmup_frames)
            for v in variants:
                d = placement.device_of(group_of(spec, v))
                if (spec.label, d) not in on_device:
                    on_device[spec.label, d] = (scenes[spec.label] if n == 1 else jax.device_put(
                        scenes[spec.label], placement.devices[d]))
                device = placement.devices[d]
                extra = {"device_index": int(device.id), "devices": n}
                progs = sequence_programs(study, spec, v, len(seq_cams),
                                          lambda *fo: compiled[program_key(spec, v, *fo)])
                jobs.append((d, partial(run_sequence, study, on_device[spec.label, d], spec,
                                        path, seq_cams, v, refs, {**env, **extra}, out_dir,
                                        progress=bar, compiled=progs),
                             f"{spec.label}/{path.name}: {v.label}"))
    if n == 1:
        for _, job, what in jobs:
            bar.set_description(what)
            st.append(job())
        return
    pools = [ThreadPoolExecutor(max_workers=1, thread_name_prefix=f"device{i}")
             for i in range(n)]
    try:
        futures = [pools[d].submit(job) for d, job, _ in jobs]
        bar.set_description(f"rendering on {n} devices")
        for f in as_completed(futures):
            st.append(f.result())
    finally:
        for pool in pools:
            pool.shutdown(wait=True, cancel_futures=True)


# ------------------------------------------------------------------ matched points

TIME_COLUMNS = ("time_ms", "time_ms_single", "sequence_ms")


def _match_seq(study: Study, spec, path, entry, m) -> str:
    """A matched point's sequence key: the entry, the match and the key of the sequence it
    aims at (a recomputed target recomputes the match), not the value it finds."""
    against = next(p for p in study.pipelines if p.label == m.against).variants[0]
    aim = [m.against, m.on, m.tolerance, m.probes, m.outside,
           sequence_key(study, spec, path, against)]
    key = Variant(m.label, entry.type, entry.params + (("match", aim), ("sweep", entry.sweep)))
    return sequence_key(study, spec, path, key)


def _run_matches(study: Study, st, env, out_dir: Path, compiled: dict, log) -> set:
    """Bisect every match of the study on every scene and path not already stored (after the
    sequences they aim at and bracket by are); returns the matched points' sequence keys."""
    found = matching.entries(study)
    seqs, scenes = set(), {}
    for spec in study.scenes:
        for path in study.paths:
            todo = [(k, e, m, _match_seq(study, spec, path, e, m)) for k, e, m in found]
            seqs |= {seq for *_, seq in todo}
            todo = [t for t in todo if not st.complete(t[3], path.frames)]
            if not todo:
                continue
            if spec.label not in scenes:
                scenes[spec.label] = backend.load_scene(spec.source, dict(spec.params))
            scene = scenes[spec.label]
            cams = backend.make_cameras(scene, rendered_path(study, path), *study.resolution)
            refs = reference_frames(scene, spec, cams[study.warmup_frames:], study.reference,
                                    study.resolution, first_frame=study.warmup_frames)
            ctx = (scene, spec, path, cams, refs, env, out_dir, compiled)
            for key, entry, m, seq in todo:
                rows = _match_one(study, st, ctx, key, entry, m, seq)
                st.append(rows)
                r = rows[0]
                log(f"match {m.label} ({spec.label}/{path.name}): {r['match_param']} = "
                    f"{r['params'][r['match_param']]:.6g} gives {m.on} {r['match_value']:.6g},"
                    f" target {r['match_target']:.6g} ({m.against}), {r['match_probes']} probes")
    return seqs


def _match_one(study: Study, st, ctx, key: str, entry, m, seq: str) -> list[dict]:
    scene, spec, path, cams, refs, env, out_dir, compiled = ctx
    (param, _), = entry.sweep

    def by_seq(v):
        return store.latest_rows(st.rows, {sequence_key(study, spec, path, v)})

    against = next(p for p in study.pipelines if p.label == m.against).variants[0]
    target = matching.mean_of(by_seq(against), m.on)
    points = [(dict(v.params)[param], matching.mean_of(by_seq(v), m.on)) for v in entry.variants]
    if target is None or any(q is None for _, q in points):
        raise StudyError(study.file, f"{key}.on", f"the rows of {m.against!r} and "
                         f"{entry.label!r} hold no number {m.on!r}")
    template = entry.variants[0]
    progs = sequence_programs(study, spec, template, len(cams), lambda n, outputs: (
        compiled.get(program_key(spec, template, n, outputs)) or compile_variant(
            study, variant_scene(scene, template), cams if n else cams[study.warmup_frames],
            template, sequence=bool(n), outputs=outputs)))

    # A probe aiming at a count or a metric is timed once, not repeated: only the final
    # render's time is kept, and only a time match needs its probes' times to be good.
    quick = study if m.on in TIME_COLUMNS else replace(
        study, timing=replace(study.timing, warmup=0, repeats=1))

    def render(value, save=False):
        v = Variant(m.label, entry.type, tuple(sorted({**dict(template.params),
                                                         param: value}.items())))
        run = type(progs)(*(p and retargeted(p, study, v) for p in progs))
        if not save and m.on not in TIME_COLUMNS:  # a probe's time is not kept
            run = run._replace(timed=None)
        return run_sequence(study if save else quick, scene, spec, path, cams, v, refs, env,
                            out_dir, compiled=run, seq=seq, save_images=save)

    try:
        out = matching.bisect(lambda x: matching.mean_of(render(x), m.on), points, target,
                              m.tolerance, m.probes, nearest=m.outside == "nearest")
    except matching.OutOfRange as e:
        raise StudyError(study.file, key, f"the target {m.on} = {target:.6g} ({m.against!r} "
                         f"on scene {spec.label!r}, path {path.name!r}) is outside the sweep: "
                         f"{e}; widen {key.rsplit('.match', 1)[0]}.sweep.{param}") from None
    rows = render(out.value, save=True)
    reached = matching.mean_of(rows, m.on)
    for r in rows:
        r.update(zip(matching.COLUMNS, (m.against, m.on, target, reached, param,
                                         out.probes + 1, out.bracketed)))
    return rows
