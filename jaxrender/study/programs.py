"""Every program a study times, compiled side by side before anything is timed (never during
timing), while the references render into the cache.

With more than two workers (or ``JAXRENDER_COMPILE_PROCESSES=1``) the programs compile in
spawned worker processes (``compile_pool``): tracing and lowering hold the GIL, so threads
would take turns on it. Otherwise (and for any program a worker cannot take) in a thread
pool: XLA compiles outside the GIL, so N cores still compile N programs at once.

On the CPU backend without worker processes every program compiles in the calling thread,
one after another, before the references render: XLA:CPU (jaxlib 0.10) segfaulted now and
then when it compiled or serialized an executable in one thread while other threads compiled
or ran programs (CI, 2026-12-01 and 2026-12-02; RESULTS.md). With worker processes on the
CPU, their executables load in one thread and the references wait for all of them.
"""

from __future__ import annotations

import dataclasses
import os
from concurrent.futures import Future, ThreadPoolExecutor
from functools import partial
from typing import NamedTuple

import jax

from jaxrender import timing
from jaxrender.pipelines import program
from jaxrender.study import (backend, compile_cache, compile_pool, executables, references,
                             shader_cost)
from jaxrender.study.specs import Study

# Programs compiled side by side at most (see compile_workers).
COMPILE_WORKERS = max(1, min(8, os.cpu_count() or 1))


def compiles_in_caller() -> bool:
    """Does every program compile in the calling thread, one at a time? On the CPU backend
    unless worker processes compile (see the module docstring)."""
    return (jax.default_backend() == "cpu"
            and not compile_pool.use_processes(COMPILE_WORKERS))


def compile_workers() -> int:
    """Programs compiled side by side: compile_ms is the wall time of a compile that shared
    the machine with this many others; the rows carry the number as compile_workers."""
    return 1 if compiles_in_caller() else COMPILE_WORKERS


class InCaller:
    """The part of an executor _Compiler uses, running each call at once in the caller's
    thread: ``submit`` returns a finished Future (holding the call's exception, if any)."""

    def submit(self, fn, *args, **kwargs) -> Future:
        out: Future = Future()
        try:
            out.set_result(fn(*args, **kwargs))
        except BaseException as e:  # the caller's .result() raises it, as a pool's would
            out.set_exception(e)
        return out

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        pass


def rendered_path(study: Study, path):
    """The path as rendered: its frames plus the study's warm-up frames before them."""
    return dataclasses.replace(path, frames=path.frames + study.warmup_frames)


def variant_scene(scene, variant):
    """The scene as ``variant`` renders it: with the variant's ``shader_cost``, if it sets one."""
    return backend.with_shader_cost(scene, shader_cost.split(dict(variant.params))[1])


def compile_variant(study: Study, scene, cameras, variant, *, sequence: bool,
                    device=None, outputs: str = "all") -> timing.Compiled:
    """The variant's sequence program over ``cameras`` (the rendered path, warm-up included)
    or, with ``sequence=False``, its single-frame program (``cameras`` one camera); it takes
    ``variant_scene(scene, variant)``, on ``device`` (default: the default device), and
    returns ``outputs`` (one of ``program.OUTPUTS``)."""
    w, h = study.resolution
    pipe = backend.pipeline(variant.type)
    params, cost = shader_cost.split(dict(variant.params))
    cfg = backend.make_config(variant.type, w, h, params)
    scene = backend.with_shader_cost(scene, cost)
    return executables.compile_program(pipe, scene, cameras, cfg, sequence=sequence,
                                       warmup_frames=study.warmup_frames if sequence else 0,
                                       device=device, outputs=outputs)


def retargeted(compiled: timing.Compiled, study: Study, variant) -> timing.Compiled:
    """``compiled`` (the program of a variant differing from ``variant`` in traced config
    fields only, such as another point of a threshold sweep) run with ``variant``'s values of
    those fields: a matched point's probes run the sweep's program, compiling nothing."""
    w, h = study.resolution
    cfg = backend.make_config(variant.type, w, h, shader_cost.split(dict(variant.params))[0])
    traced = program.split_config(cfg)[1]
    return dataclasses.replace(compiled, call=partial(compiled.call, traced=traced))


def program_key(spec, variant, frames: int = 0, outputs: str = "all") -> tuple:
    """One compiled program per scene, variant, sequence length (0: the single-frame program)
    and outputs: the points of a sweep share a label, so the key holds their parameters too."""
    return spec.label, variant.label, variant.params_json, frames, outputs


class SequencePrograms(NamedTuple):
    """The compiled programs one sequence runs (``roles``)."""

    instrumented: timing.Compiled  # images, counts and views: what the rows are made of
    timed: timing.Compiled | None = None  # images only; None: the instrumented one is timed
    single: timing.Compiled | None = None  # the single-frame program, timed beside


def roles(study: Study, frames: int) -> dict[str, tuple[int, str]]:
    """{role in SequencePrograms: (frames, outputs)} of a sequence of ``frames`` frames
    (warm-up included): its instrumented program; with ``timing.outputs = "images"`` the
    images-only program it times; with ``timing.single_frame`` its single-frame program,
    returning ``timing.outputs`` (only its time is kept)."""
    out = {"instrumented": (frames, "all")}
    if study.timing.outputs == "images":
        out["timed"] = (frames, "images")
    if study.timing.single_frame:
        out["single"] = (0, study.timing.outputs)
    return out


def sequence_programs(study: Study, spec, variant, frames: int, get) -> SequencePrograms:
    """The SequencePrograms of ``variant``'s sequence of ``frames`` frames on ``spec``'s
    scene: ``get(frames, outputs)`` gives each role's compiled program."""
    return SequencePrograms(**{role: get(*fo) for role, fo in roles(study, frames).items()})


class _Compiler:
    """Submits compiles to worker processes (falling back to threads) or to threads."""

    def __init__(self, study: Study, scenes: dict):
        self.study, self.scenes = study, scenes
        # On the CPU no XLA work runs beside another (see the module docstring): programs
        # compile in the caller, or worker processes' executables load in one thread.
        self.cpu = jax.default_backend() == "cpu"
        self.threads = (InCaller() if compiles_in_caller()
                        else ThreadPoolExecutor(max_workers=1 if self.cpu else COMPILE_WORKERS))
        self.procs = (compile_pool.ProcessCompiler(COMPILE_WORKERS, self.threads)
                      if compile_pool.use_processes(COMPILE_WORKERS) else None)

    def submit(self, label, spec, path, pipe, params, sequence, fn, *args, thread=False,
               outputs="all"):
        """fn(*args) in a thread, or the program of pipeline ``pipe`` with ``params`` in a
        worker process with fn(*args) as the fallback; ``thread``: a thread in any case (a
        worker process compiles for its own first device only)."""
        if self.procs is None or thread:
            return self.threads.submit(fn, *args)
        study = self.study
        params, cost = shader_cost.split(dict(params))
        # backend.load_scene reads the cost from the scene parameters: the worker's scene
        # cache tells the costs apart.
        costs = () if cost is None else ((shader_cost.KEY, cost),)
        try:
            job = compile_pool.Job(
                backend.load_scene, backend.make_cameras, spec.source,
                tuple(dict(spec.params).items()) + costs, rendered_path(study, path),
                tuple(study.resolution), backend.pipeline(pipe),
                backend.make_config(pipe, *study.resolution, params),
                sequence=sequence, warmup_frames=study.warmup_frames if sequence else 0,
                outputs=outputs, scene=backend.with_shader_cost(self.scenes[spec.label], cost))
        except Exception:  # fn raises it again, where the thread path would
            return self.threads.submit(fn, *args)
        return self.procs.submit(label, job, lambda: fn(*args))

    def close(self):
        if self.procs is not None:
            self.procs.shutdown()
        self.threads.shutdown(wait=True, cancel_futures=True)


def compile_all(study: Study, todo, scenes: dict, cams: dict, device_of=None) -> dict:
    """Compile every program of ``todo`` (per scene, variant and path length the programs of
    ``roles``), and the reference program of each scene whose
    references are not all cached, while this thread renders the references into the cache.
    ``cams[scene label, path name]`` are the rendered path's cameras (warm-up included).
    Returns {program_key: Compiled}. Programs in the executable store are loaded from it;
    the others compile with JAX's cache suspended, so that each can be stored.
    ``device_of(spec, variant)``: the device a variant's programs run on (default: the
    default device)."""
    if executables.enabled():
        with compile_cache.suspended(), executables.deferred_stores():
            return _compile_all(study, todo, scenes, cams, device_of)
    return _compile_all(study, todo, scenes, cams, device_of)


def _compile_all(study: Study, todo, scenes: dict, cams: dict, device_of=None) -> dict:
    comp = _Compiler(study, scenes)
    pairs = {(s.label, p.name): (s, p) for s, p, _ in todo}
    warm, ref = study.warmup_frames, study.reference
    try:
        # Tracing holds the GIL, so the longest chains start first: references (this thread
        # renders them while the rest compiles), then programs with host-side preparation
        # (object-space charts), then the others.
        ref_programs: dict = {}
        for spec, path in pairs.values():
            ref_cams = cams[spec.label, path.name][warm:]
            if spec.label not in ref_programs and not references.all_cached(
                    spec, ref_cams, ref, study.resolution, first_frame=warm,
                    moving=getattr(scenes[spec.label], "animation", None) is not None):
                ref_programs[spec.label] = comp.submit(
                    f"the reference of {spec.label}", spec, path, ref.pipeline, ref.params,
                    False, references.compile_reference, scenes[spec.label], ref_cams[0], ref,
                    study.resolution)
        futures, aliases = _submit_variants(comp, study, todo, scenes, cams, device_of)
        if comp.cpu:  # nor beside the references
            for f in [*futures.values(), *ref_programs.values()]:
                f.exception()
        for spec, path in pairs.values():
            references.reference_frames(scenes[spec.label], spec,
                                        cams[spec.label, path.name][warm:], ref,
                                        study.resolution, programs=ref_programs,
                                        first_frame=warm)
        out = {key: f.result() for key, f in futures.items()}
        return out | {key: retargeted(out[first], study, v)
                      for key, (first, v) in aliases.items()}
    finally:
        comp.close()


def program_identity(spec, variant, frames: int = 0, outputs: str = "all") -> tuple:
    """What a program is compiled from: its key less the config's TRACED_FIELDS, which are
    the program's arguments (the points of a threshold sweep share one program, and so one
    device)."""
    traced = backend.pipeline(variant.type).config_cls.TRACED_FIELDS
    rest = tuple((k, v) for k, v in variant.params if k not in traced)
    return spec.label, variant.type, repr(rest), frames, outputs


def _submit_variants(comp: _Compiler, study: Study, todo, scenes: dict, cams: dict,
                     device_of=None):
    """({program_key: Future} of the programs compiled, {program_key: (the key of the program
    it runs with other traced values, variant)})."""
    futures: dict = {}
    aliases: dict = {}
    first: dict = {}
    warm = study.warmup_frames
    prepares = lambda t: backend.pipeline(t[2].type).prepares  # noqa: E731
    default = jax.devices()[0]
    for spec, path, v in sorted(todo, key=lambda t: not prepares(t)):
        seq_cams = cams[spec.label, path.name]
        device = device_of(spec, v) if device_of else None
        elsewhere = device is not None and device != default
        for frames, outputs in roles(study, len(seq_cams)).values():
            key = program_key(spec, v, frames, outputs)
            same = first.setdefault(program_identity(spec, v, frames, outputs), key)
            if same != key and key not in futures:
                aliases[key] = (same, v)
                continue
            if key not in futures:
                what = (f"{spec.label}/{v.label}" + (f" ({frames} frames)" if frames else "")
                        + (" (images)" if outputs == "images" else ""))
                args = (seq_cams, v) if frames else (seq_cams[warm], v)
                fn = partial(compile_variant, sequence=bool(frames),
                             device=device if elsewhere else None, outputs=outputs)
                futures[key] = comp.submit(what, spec, path, v.type, v.params, bool(frames),
                                           fn, study, scenes[spec.label], *args,
                                           thread=elsewhere, outputs=outputs)
    return futures, aliases
