"""JAX's persistent compilation cache, kept under jaxrender's cache directory, so a study rerun
loads the executables it compiled before instead of compiling them again.

Every program is cached, however quick its compile (JAX's default skips those under a second,
which on a GPU is most of a study's programs). A ``JAX_COMPILATION_CACHE_DIR`` in the
environment wins; ``JAXRENDER_COMPILATION_CACHE=0`` turns the cache off. On the CPU backend it is
off unless ``JAXRENDER_COMPILATION_CACHE=1`` asks for it: XLA:CPU aborted twice inside this
cache's write (serializing an executable) during the test suite. Compile workers inherit the
setting with the rest of the parent's ``jax.config``.
"""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path

import jax
from jax.experimental.compilation_cache import compilation_cache

from jaxrender.study.cache import cache_root

ENV_CACHE = "JAXRENDER_COMPILATION_CACHE"
_EVENTS = {"/jax/compilation_cache/cache_hits": "hits",
           "/jax/compilation_cache/cache_misses": "misses"}
_counts = {"hits": 0, "misses": 0}
_lock = threading.Lock()
_listening = False
# JAX reports its events in the thread that compiles, so a thread can tell how its own
# compile went while other threads compile beside it: XLA ran (a compile, or a load from
# this cache), and whether it loaded from this cache. An executable JAX keeps in memory
# reports neither.
BACKEND_COMPILE_EVENT = "/jax/core/compile/backend_compile_duration"
_this_thread = threading.local()


def default_dir() -> Path:
    return cache_root() / "xla"


def _count(event: str, **_) -> None:
    key = _EVENTS.get(event)
    if key:
        with _lock:
            _counts[key] += 1
        if key == "hits":
            _this_thread.hits = getattr(_this_thread, "hits", 0) + 1


def _count_compile(event: str, duration: float, **_) -> None:
    if event == BACKEND_COMPILE_EVENT:
        _this_thread.compiles = getattr(_this_thread, "compiles", 0) + 1


def _listen() -> None:
    global _listening
    with _lock:
        if not _listening:
            jax.monitoring.register_event_listener(_count)
            jax.monitoring.register_event_duration_secs_listener(_count_compile)
            _listening = True


def env_flag(name: str) -> bool | None:
    """An on/off environment variable: True (1, true, yes, on), False (0, false, no, off), or
    None when unset or anything else."""
    v = os.environ.get(name, "").strip().lower()
    return True if v in ("1", "true", "yes", "on") else False if v in (
        "0", "false", "no", "off") else None


def turned_off() -> bool:
    """``JAXRENDER_COMPILATION_CACHE=0`` (or false, no, off): no persistent cache, no
    executable store."""
    return env_flag(ENV_CACHE) is False


def wanted() -> bool:
    """Should studies use the persistent cache? ``JAXRENDER_COMPILATION_CACHE`` says so; unset,
    yes except on the CPU backend."""
    said = env_flag(ENV_CACHE)
    return jax.default_backend() != "cpu" if said is None else said


def enable(directory: Path | None = None) -> Path | None:
    """Turn the persistent cache on (idempotent) where it is ``wanted``; the folder used, or
    None when it is off."""
    if not wanted():
        return None
    users = os.environ.get("JAX_COMPILATION_CACHE_DIR")
    folder = Path(directory or users or default_dir())
    folder.mkdir(parents=True, exist_ok=True)
    if str(folder) != jax.config.values.get("jax_compilation_cache_dir"):
        jax.config.update("jax_compilation_cache_dir", str(folder))
        compilation_cache.reset_cache()  # JAX opens its cache folder once per process
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    _listen()
    return folder


def thread_compiles() -> tuple[int, int]:
    """(XLA compiles, loads from the persistent cache among them) of this thread so far."""
    _listen()
    return getattr(_this_thread, "compiles", 0), getattr(_this_thread, "hits", 0)


@contextlib.contextmanager
def suspended():
    """The persistent cache off for every compile inside (all threads), restored after: for
    programs whose executables are serialized, since on XLA:CPU an executable loaded from the
    cache serializes without its code. Callers hold no other compiles during it."""
    folder = jax.config.values.get("jax_compilation_cache_dir")
    enabled = jax.config.values.get("jax_enable_compilation_cache", True)
    if not folder or not enabled:
        yield
        return
    jax.config.update("jax_enable_compilation_cache", False)
    compilation_cache.reset_cache()  # JAX decides once per process whether its cache is used
    try:
        yield
    finally:
        jax.config.update("jax_enable_compilation_cache", True)
        compilation_cache.reset_cache()


def counts() -> dict:
    """Programs found in (hits) and added to (misses) the cache by this process so far."""
    with _lock:
        return dict(_counts)


def describe(before: dict) -> str:
    """``" (compilation cache: 3 loaded, 9 compiled)"`` since ``before`` (this process only:
    programs compiled in worker processes are not counted), or "" when nothing was asked."""
    now = counts()
    hits, misses = now["hits"] - before["hits"], now["misses"] - before["misses"]
    if not (hits or misses):
        return ""
    return f" (compilation cache: {hits} loaded, {misses} compiled)"
