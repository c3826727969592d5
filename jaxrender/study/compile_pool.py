"""Compile study programs in spawned worker processes, so that tracing and lowering (Python,
under the GIL) run in parallel and not only XLA's compile.

Each job names a scene (``load_scene(source, params)``, or carries it loaded), a camera path
(``make_cameras(scene, path, width, height)``), a registered Pipeline and its config, and
whether it is the single-frame program (first camera) or the sequence program (the whole path,
with ``warmup_frames`` dropped). The worker loads the scene itself (cached per worker), prepares
the program's arguments, reads its executable from the executable store (``executables``) or
lowers, compiles and stores it as the in-process path does, and returns the executable
serialized with ``jax.experimental.serialize_executable`` beside the program's ``Prepared``
arguments (object-space's sheet, traced config values); the parent deserializes it onto its
first device and binds it (``program.bind``) into a ``timing.Compiled`` whose compile_ms is
the worker's preparation and lower+compile (or store read) time.

Every job that cannot go through a worker (unpicklable pieces, a worker error, an executable
that does not serialize, a broken pool) is compiled by the caller's ``fallback`` in a thread
instead, with a logged note: a program is never dropped.

``JAXRENDER_COMPILE_TIMELINE=1`` makes each worker print one line per program to stderr: wall
clock start and end, and the seconds spent getting the scene, preparing the arguments (with
any host-side preparation) and reading the store, and lowering and compiling, to find which
programs make a study's critical path.

Workers are started with "spawn" (never "fork": the parent has JAX/CUDA threads), without the
parent's ``__main__`` (as ``jaxrender.figures.parallel`` does), with
``XLA_PYTHON_CLIENT_PREALLOCATE=false`` in their environment from the start (a worker compiles,
it must not hold GPU memory; set around the spawn, so it holds whatever a worker imports
first) and the parent's ``jax.config`` values; the rest of the environment (JAX_PLATFORMS,
XLA_FLAGS, ...) is inherited.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Callable

from jaxrender.spawning import main_hidden
from jaxrender.study.compile_cache import env_flag

log = logging.getLogger("jaxrender.study")

ENV = "JAXRENDER_COMPILE_PROCESSES"


def use_processes(workers: int) -> bool:
    """Compile in worker processes? ``JAXRENDER_COMPILE_PROCESSES=1`` forces it, ``=0``
    forbids it; otherwise only with more than two workers (the 2-core CI machine keeps
    threads)."""
    forced = env_flag(ENV)
    return workers > 2 if forced is None else forced


@dataclass(frozen=True)
class Job:
    """One program to compile in a worker: everything is pickled by value or by reference."""

    load_scene: Callable  # backend.load_scene
    make_cameras: Callable  # backend.make_cameras
    source: str
    scene_params: tuple  # items of the scene's parameters
    path: Any  # specs.PathSpec (its frames include the warm-up frames)
    resolution: tuple  # (width, height)
    pipeline: Any  # the registered Pipeline
    cfg: Any  # its config
    sequence: bool = False  # the sequence program over the path, else the single frame
    warmup_frames: int = 0
    outputs: str = "all"  # one of program.OUTPUTS
    # The loaded scene, when the parent has it: a worker then loads nothing (loading can
    # compile programs of its own, a shadow map's rasterizer, in every worker again).
    scene: Any = None


# ------------------------------------------------------------------ worker side

_SCENES: dict = {}  # (loader, source, params) -> scene, per worker process
_CAMERAS: dict = {}


def _init_worker(config_values: dict) -> None:
    import jax

    current = jax.config.values
    for name, value in config_values.items():
        try:
            if current.get(name, value) != value:
                jax.config.update(name, value)
        except Exception:  # an option that cannot change after start: leave it
            pass


def _cameras(job: Job):
    skey = (job.load_scene, job.source, job.scene_params)
    scene = _SCENES.get(skey)
    if scene is None and job.scene is not None:
        scene = _SCENES[skey] = job.scene
    if scene is None:
        scene = _SCENES[skey] = job.load_scene(job.source, dict(job.scene_params))
    ckey = skey + (job.make_cameras, job.path, tuple(job.resolution))
    cams = _CAMERAS.get(ckey)
    if cams is None:
        cams = _CAMERAS[ckey] = job.make_cameras(scene, job.path, *job.resolution)
    return scene, (cams if job.sequence else cams[0])


def compile_job(payload: bytes) -> bytes:
    """Worker: the pickled Job -> pickled (compile_ms, executable bytes (``executables.pack``),
    prepared, stored: whether they came from the executable store). The job and the result
    travel as bytes so that a (un)pickling error is this job's error, never the pool's."""
    from jaxrender.pipelines import program
    from jaxrender.study import executables

    job: Job = pickle.loads(payload)
    started, t_start = time.time(), time.perf_counter()
    scene, cams = _cameras(job)
    t0 = time.perf_counter()
    fixed, args, prepared = program.arguments(job.pipeline, scene, cams, job.cfg,
                                              sequence=job.sequence,
                                              warmup_frames=job.warmup_frames,
                                              outputs=job.outputs)
    key = executables.program_key(job.pipeline, fixed, args)
    exe = executables.read(key)
    t_prepared = time.perf_counter()
    stored = exe is not None
    if not stored:
        compiled, exe = executables.compile_fresh(key, fixed, args)
        exe = exe if exe is not None else executables.pack(compiled)
    t_end = time.perf_counter()
    if os.environ.get("JAXRENDER_COMPILE_TIMELINE"):
        import sys

        print(f"TIMELINE pid={os.getpid()} {job.source} {type(job.cfg).__name__} "
              f"sequence={job.sequence} outputs={job.outputs} start={started:.2f} "
              f"scene_s={t0 - t_start:.2f} "
              f"prepare_s={t_prepared - t0:.2f} compile_s={t_end - t_prepared:.2f} "
              f"stored={stored} end={started + t_end - t_start:.2f}", file=sys.stderr,
              flush=True)
    return pickle.dumps(((t_end - t0) * 1e3, exe, prepared, stored))


# ------------------------------------------------------------------ parent side


@contextlib.contextmanager
def _worker_environment():
    """The environment a worker is spawned with: the parent's, without GPU preallocation."""
    old = os.environ.get("XLA_PYTHON_CLIENT_PREALLOCATE")
    os.environ["XLA_PYTHON_CLIENT_PREALLOCATE"] = "false"
    try:
        yield
    finally:
        if old is None:
            del os.environ["XLA_PYTHON_CLIENT_PREALLOCATE"]
        else:
            os.environ["XLA_PYTHON_CLIENT_PREALLOCATE"] = old


def load(result: bytes, job: Job):
    """The parent's ``timing.Compiled`` from a worker's result."""
    from jaxrender import timing
    from jaxrender.pipelines import program
    from jaxrender.study import executables

    ms, exe, prepared, stored = pickle.loads(result)
    call = program.bind(job.pipeline, job.cfg, executables.unpack(exe), prepared)
    executables.note_worker_program(stored)
    return timing.Compiled(call, float(ms), "stored" if stored else "aot")


class ProcessCompiler:
    """``submit(label, job, fallback) -> Future[timing.Compiled]``: compiled in a worker
    process and loaded in one of ``threads``; on any failure, ``fallback()`` (in-process
    compile) runs in ``threads`` instead, with a logged note."""

    def __init__(self, workers: int, threads: ThreadPoolExecutor):
        self.workers = max(1, workers)
        self.threads = threads
        self._procs = None
        self._lock = threading.Lock()
        self._closing = False
        self.fallbacks: list[str] = []  # labels compiled in a thread instead (and why)

    def _pool(self):
        if self._procs is None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            import jax

            values = {}
            for k, v in jax.config.values.items():
                try:
                    pickle.dumps(v)
                except Exception:
                    continue
                values[k] = v
            if jax.default_backend() == "cpu":
                # An XLA:CPU executable loaded from the persistent cache serializes without
                # its code ("Function ... not found" when the parent runs it), so CPU workers
                # always compile; a GPU executable from the cache travels whole.
                values["jax_compilation_cache_dir"] = None
            self._procs = ProcessPoolExecutor(
                max_workers=self.workers, mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_worker, initargs=(values,))
        return self._procs

    def _fallback(self, label: str, why: str, fallback: Callable, out: Future) -> None:
        note = f"compiling {label} in a thread instead of a worker process: {why}"
        log.warning(note)
        with self._lock:
            self.fallbacks.append(note)
        try:
            out.set_result(fallback())
        except BaseException as e:
            out.set_exception(e)

    def submit(self, label: str, job: Job, fallback: Callable[[], Any]) -> Future:
        out: Future = Future()
        try:
            with main_hidden(), _worker_environment():  # workers spawn as jobs arrive
                payload = pickle.dumps(job)
                pf = self._pool().submit(compile_job, payload)
        except Exception as e:
            self.threads.submit(self._fallback, label, f"{type(e).__name__}: {e}", fallback,
                                out)
            return out

        def done(pf):
            if self._closing:
                out.cancel()
                return
            try:
                self.threads.submit(self._finish, label, job, pf, fallback, out)
            except RuntimeError:  # the thread pool is shut down: the caller is gone
                out.cancel()

        pf.add_done_callback(done)
        return out

    def _finish(self, label, job, pf, fallback, out: Future) -> None:
        try:
            res = load(pf.result(), job)
        except Exception as e:
            if self._closing:
                out.cancel()
                return
            self._fallback(label, f"{type(e).__name__}: {e}", fallback, out)
            return
        out.set_result(res)

    def shutdown(self) -> None:
        self._closing = True
        if self._procs is not None:
            self._procs.shutdown(wait=True, cancel_futures=True)


__all__ = ["ENV", "Job", "ProcessCompiler", "compile_job", "load", "use_processes"]
