"""The executable store: the study's compiled programs on disk, found again without tracing.

JAX's persistent compilation cache (``compile_cache``) keys on the lowered program, so a rerun
still traces and lowers every program before it can load one. This store keys on what the
program is built from instead, all known before tracing: the product sources (the reference
cache's code version, plus the files that define the pipeline), jax and jaxlib, the device and
host, XLA_FLAGS and jax's configuration, the pipeline, its static config and the program's mode,
and the argument avals (the pytree structure, with its static fields, and each leaf's shape,
dtype and weak type, read off the concrete arguments). A hit is loaded with
``jax.experimental.serialize_executable`` and skips lowering and compiling.

Entries live in ``$JAXRENDER_CACHE/executables/``, one file per program, written to a temporary
name and renamed, with a digest of their contents: a partial, corrupt or unloadable entry is a
miss (logged), never a failed study. Storing may fail too (logged, the study goes on). Only
an executable XLA compiled just now is stored, never one loaded from JAX's cache (on XLA:CPU
such an executable serializes without its code and fails only when it runs) nor one jax kept
in memory (which may have been loaded so): the study compiles what the store misses with
JAX's cache suspended (``compile_cache.suspended``), and each compile's own events say how it
went. ``JAXRENDER_COMPILATION_CACHE=0`` turns the store off with the cache; it is off by
default on the CPU backend (``enabled``).

Loading an entry runs code from it: the store is as trusted as the cache folder it lives in.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import logging
import os
import pickle
import platform
import sys
import threading
import time
from pathlib import Path

import jax

from jaxrender import timing
from jaxrender.pipelines import dispatch, program
from jaxrender.study import cache, compile_cache

log = logging.getLogger("jaxrender.study")

SUFFIX = ".jaxexe"
ENV_STORE = "JAXRENDER_EXECUTABLE_STORE"
_MAGIC = b"jaxrender executable 1\n"
# jax options that change no program: where caches and logs go.
_NEUTRAL_OPTIONS = ("cache", "log", "dump", "explain")
_counts = {"loaded": 0, "compiled": 0, "unstored": 0}
_lock = threading.Lock()
_pending: list | None = None  # executables to store when deferred_stores' block ends


class SharedExclusive:
    """Compiles may overlap one another; serializing or loading an executable overlaps none
    (XLA:CPU segfaulted once as one thread serialized while another compiled; a later crash
    came from a compile alone, so this narrows the risk rather than removing it)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._shared = 0
        self._exclusive = False
        self._waiting = 0

    def shared(self):
        return _Hold(self, exclusive=False)

    def exclusive(self):
        return _Hold(self, exclusive=True)

    def waiting(self) -> int:
        """How many exclusive holds wait."""
        with self._cond:
            return self._waiting

    def acquire(self, exclusive: bool) -> None:
        with self._cond:
            if exclusive:
                self._waiting += 1
                self._cond.wait_for(lambda: not self._exclusive and self._shared == 0)
                self._waiting -= 1
                self._exclusive = True
            else:  # an exclusive hold that waits goes first, so it is never starved
                self._cond.wait_for(lambda: not self._exclusive and self._waiting == 0)
                self._shared += 1

    def release(self, exclusive: bool) -> None:
        with self._cond:
            if exclusive:
                self._exclusive = False
            else:
                self._shared -= 1
            self._cond.notify_all()


@dataclasses.dataclass
class _Hold:
    guard: SharedExclusive
    exclusive: bool

    def __enter__(self):
        self.guard.acquire(self.exclusive)

    def __exit__(self, *exc):
        self.guard.release(self.exclusive)


_xla = SharedExclusive()


def folder() -> Path:
    return cache.cache_root() / "executables"


def enabled() -> bool:
    """Is the store on? ``JAXRENDER_EXECUTABLE_STORE=1`` or ``=0`` says so; by default it is
    on except on the CPU backend, where XLA segfaulted compiling in a process that had
    serialized many executables before (the test suite, twice).
    ``JAXRENDER_COMPILATION_CACHE=0`` turns it off in any case."""
    if compile_cache.turned_off():
        return False
    said = compile_cache.env_flag(ENV_STORE)
    return jax.default_backend() != "cpu" if said is None else said


def _count(what: str) -> None:
    with _lock:
        _counts[what] += 1


def counts() -> dict:
    """Programs loaded from the store, compiled (while it was on) and not stored, so far."""
    with _lock:
        return dict(_counts)


def describe(before: dict) -> str:
    """``" (executable store: 10 loaded, 2 compiled)"`` since ``before``; "" when nothing was
    asked of the store."""
    now = counts()
    n = {k: now[k] - before[k] for k in now}
    if not (n["loaded"] or n["compiled"]):
        return ""
    unstored = f", {n['unstored']} not stored" if n["unstored"] else ""
    return f" (executable store: {n['loaded']} loaded, {n['compiled']} compiled{unstored})"


# ------------------------------------------------------------------ the key


def _host() -> list:
    """What an XLA:CPU executable is built for: the processor and its instruction sets."""
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            lines = [ln for ln in f if ln.startswith(("model name", "flags"))]
        cpu = hashlib.sha256("".join(sorted(set(lines))).encode()).hexdigest()[:16]
    except OSError:
        pass
    return [platform.machine(), platform.processor(), cpu]


def _parts(fn) -> list:
    """``fn`` and what it wraps (a FrameStep's frame, a partial's function)."""
    inner = [getattr(fn, "__wrapped__", None), getattr(fn, "func", None)]
    if dataclasses.is_dataclass(fn) and not isinstance(fn, type):
        inner += [getattr(fn, f.name) for f in dataclasses.fields(fn)]
    return [fn] + [f for f in inner if callable(f)]


def _sources(pipe) -> list:
    """Digests of the files defining the pipeline's functions and config (a pipeline
    registered from outside the package is not in the code version)."""
    names = set()
    for fn in (pipe.step, pipe.init, pipe.prepare, pipe.config_cls):
        for part in _parts(fn):
            names.add(getattr(part, "__module__", None) or type(part).__module__)
    out = []
    for name in sorted(names):
        path = getattr(sys.modules.get(name), "__file__", None)
        if path is None:
            raise ValueError(f"no source file for module {name!r}")
        out.append(hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16])
    return out


def _environment() -> dict:
    import jaxlib

    dev = jax.devices()[0]
    options = {k: repr(v) for k, v in jax.config.values.items()
               if not any(word in k for word in _NEUTRAL_OPTIONS)}
    return {"code": cache.code_version(), "jax": [jax.__version__, jaxlib.__version__],
            "device": [dev.platform, dev.device_kind, dev.client.platform_version, dev.id],
            "host": _host() if dev.platform == "cpu" else [],
            "xla_flags": os.environ.get("XLA_FLAGS", ""), "jax_config": options,
            "launch_mode": [dispatch.launch_mode(), dispatch.named_launch_mode()]}


def program_key(pipe, fixed, args, device=None) -> str | None:
    """The store's key of the program with static jit arguments ``fixed`` (pipeline, static
    config, mode, outputs) and dynamic arguments ``args`` (``program.arguments``); None when
    the store is off or the program cannot be named without tracing (an argument that is no
    array, a static value whose repr is an address)."""
    if not enabled():
        return None
    _, static_cfg, mode, outputs = fixed
    try:
        leaves, treedef = jax.tree_util.tree_flatten(args)
        avals = [jax.typeof(x) for x in leaves]
        # Pickled as well as written out: a repr may leave a field out, a pickle does not.
        statics = hashlib.sha256(pickle.dumps((static_cfg, mode, outputs, treedef))).hexdigest()
        parts = {**_environment(), "pipeline": [pipe.name, _sources(pipe)],
                 "config": repr(static_cfg), "mode": repr(mode), "outputs": outputs,
                 "tree": str(treedef),
                 "statics": statics, "target": None if device is None else int(device.id),
                 "avals": [[str(a.dtype), list(a.shape), bool(a.weak_type)] for a in avals]}
    except (TypeError, ValueError, OSError, AttributeError, pickle.PicklingError) as e:
        log.info("executable store: %s cannot be keyed (%s: %s)", pipe.name,
                 type(e).__name__, e)
        return None
    text = json.dumps(parts, sort_keys=True)
    if " at 0x" in text:
        return None
    return hashlib.sha256(text.encode()).hexdigest()[:40]


# ------------------------------------------------------------------ entries


def _path(key: str) -> Path:
    return folder() / f"{key}{SUFFIX}"


def pack(compiled) -> bytes:
    """A compiled jax program as bytes (executable and pytree structures)."""
    from jax.experimental.serialize_executable import serialize

    with _xla.exclusive():
        return pickle.dumps(serialize(compiled))


def unpack(payload: bytes, device=None):
    """The jax Compiled program of ``pack``'s bytes, loaded onto ``device`` (default: the
    first device)."""
    from jax.experimental.serialize_executable import deserialize_and_load

    exe, in_tree, out_tree = pickle.loads(payload)
    dev = jax.devices()[0] if device is None else device
    with _xla.exclusive():
        return deserialize_and_load(exe, in_tree, out_tree, backend=dev.client,
                                    execution_devices=[dev])


def read(key: str | None) -> bytes | None:
    """The entry's bytes, or None when there is none or it is damaged (logged)."""
    if key is None:
        return None
    p = _path(key)
    try:
        blob = p.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as e:
        log.warning("executable store: cannot read %s (%s); compiling", p, e)
        return None
    head, digest = len(_MAGIC), len(_MAGIC) + 32
    payload = blob[digest:]
    if blob[:head] != _MAGIC or blob[head:digest] != hashlib.sha256(payload).digest():
        log.warning("executable store: %s is damaged; compiling", p)
        return None
    return payload


def write(key: str | None, payload: bytes) -> bool:
    """Store ``payload`` under ``key`` atomically; False (logged) when it cannot."""
    if key is None:
        return False
    p = _path(key)
    tmp = p.with_name(f".{p.stem}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as f:
            f.write(_MAGIC + hashlib.sha256(payload).digest() + payload)
        os.replace(tmp, p)
        return True
    except OSError as e:
        log.warning("executable store: cannot write %s (%s); the study goes on", p, e)
        tmp.unlink(missing_ok=True)
        return False


def compile_fresh(key: str | None, fixed, args):
    """(jax Compiled, its bytes or None): lowered and compiled, then stored under ``key``
    when XLA compiled it just now (not JAX's cache, nor an executable jax kept in memory,
    which may have come from that cache) and it serializes; else logged, and the study goes
    on."""
    lowered = program.lower_arguments(fixed, args)
    before = compile_cache.thread_compiles()
    with _xla.shared():
        compiled = lowered.compile()
    if key is None:
        return compiled, None
    ran, loaded = (b - a for a, b in zip(before, compile_cache.thread_compiles()))
    name = fixed[0].name
    if loaded:
        _not_stored(name, "it was loaded from JAX's compilation cache")
    elif not ran:
        _not_stored(name, "jax had it in memory already")
    else:
        with _lock:
            if _pending is not None:
                _pending.append((key, compiled, name))
                return compiled, None
        return compiled, _store(key, compiled, name)
    return compiled, None


def _not_stored(name: str, why: str) -> None:
    log.info("executable store: %s not stored: %s", name, why)
    _count("unstored")


def _store(key: str, compiled, name: str) -> bytes | None:
    """Pack and write one executable; its bytes, or None (logged) when it does not pack."""
    try:
        payload = pack(compiled)
    except Exception as e:  # an executable that does not serialize is still usable
        _not_stored(name, f"{type(e).__name__}: {e}")
        return None
    if not write(key, payload):
        _not_stored(name, "it could not be written")
    return payload


@contextlib.contextmanager
def deferred_stores():
    """Store the executables compiled inside the block when it ends, one after another in
    this thread, so that no pack runs beside a compile in another thread, including compiles
    that do not go through this module (the guard covers only those that do)."""
    global _pending
    with _lock:
        outer, _pending = _pending, []
    try:
        yield
    finally:
        with _lock:
            todo, _pending = _pending, outer
        for key, compiled, name in todo:
            _store(key, compiled, name)


def note_worker_program(stored: bool) -> None:
    """Count a program a compile worker loaded from the store (``stored``) or compiled."""
    if enabled():
        _count("loaded" if stored else "compiled")


def compile_program(pipe, scene, cameras, cfg, *, sequence: bool = False,
                    warmup_frames: int = 0, device=None, outputs: str = "all"
                    ) -> timing.Compiled:
    """``timing.compile_program`` through the store: loaded when stored (method "stored",
    compile_ms the preparation and load), else compiled and stored. ``device``: the device
    it runs on (default: the first), a part of the store's key; ``outputs``: one of
    ``program.OUTPUTS``."""
    t0 = time.perf_counter()
    fixed, args, prepared = program.arguments(pipe, scene, cameras, cfg, sequence=sequence,
                                              warmup_frames=warmup_frames, outputs=outputs)
    if device is not None:  # committed arguments: the program is lowered for that device
        args = jax.device_put(args, device)
    key = program_key(pipe, fixed, args, device)
    payload = read(key)
    if payload is not None:
        try:
            compiled = unpack(payload, device)
        except Exception as e:
            log.warning("executable store: %s does not load (%s: %s); compiling",
                        _path(key), type(e).__name__, e)
        else:
            _count("loaded")
            return timing.Compiled(program.bind(pipe, cfg, compiled, prepared),
                                   (time.perf_counter() - t0) * 1e3, "stored")
    compiled, _ = compile_fresh(key, fixed, args)
    if enabled():
        _count("compiled")
    return timing.Compiled(program.bind(pipe, cfg, compiled, prepared),
                           (time.perf_counter() - t0) * 1e3)


__all__ = ["ENV_STORE", "SUFFIX", "SharedExclusive", "compile_fresh", "compile_program", "counts",
           "deferred_stores", "describe", "enabled", "folder", "note_worker_program", "pack",
           "program_key", "read", "unpack", "write"]
