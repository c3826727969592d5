"""Keeping a process's memory mappings under the kernel's limit while it compiles on the CPU.

XLA:CPU maps a few memory regions for every kernel of a program it loads (about a thousand for
one pipeline program) and unmaps them only when the executable is freed; jax's caches keep
every executable they compiled, referenced or not, for the life of the process. Linux caps a
process's mappings at ``vm.max_map_count`` (65,530 by default), and XLA's next mmap past it
fails as a segfault inside the compiler. ``release_if_crowded`` drops jax's caches once a
process is past half the limit: programs a caller still holds stay, the rest are freed (and
compile again if asked for). A GPU's kernels live on the device: nothing to do there.
"""

from __future__ import annotations

import gc
import threading
import time
from pathlib import Path

import jax

MAP_COUNT_FILE = Path("/proc/sys/vm/max_map_count")
MAPS_FILE = Path("/proc/self/maps")
# Reading the maps costs the kernel about 3.5 us a region (0.1 s at 30,000), so a caller that
# asks often is answered from its last count for this long.
RECOUNT_S = 2.0
_last_count = [-RECOUNT_S]  # when the regions were last counted (time.monotonic)


def map_limit() -> int | None:
    """The process's mapping limit, or None where there is none to read (not Linux)."""
    try:
        return int(MAP_COUNT_FILE.read_text())
    except (OSError, ValueError):
        return None


def mapped_regions() -> int | None:
    """How many memory regions this process maps now (None where it cannot be read)."""
    try:
        with MAPS_FILE.open("rb") as maps:
            return sum(1 for _ in maps)
    except OSError:
        return None


def release_if_crowded(fraction: float = 0.5, *, now: bool = False) -> bool:
    """On the CPU backend, past ``fraction`` of the mapping limit: drop jax's caches and
    collect, freeing every compiled program nothing else holds. Counts the regions at most
    every RECOUNT_S seconds (between counts it answers False at once) unless ``now``. Only in
    the main thread: a study's loader thread must not drop the caches under a trace in
    another. Returns whether it released."""
    if jax.default_backend() != "cpu" or threading.current_thread() is not threading.main_thread():
        return False
    limit = map_limit()
    if limit is None:
        return False
    t = time.monotonic()
    if not now and t - _last_count[0] < RECOUNT_S:
        return False
    _last_count[0] = t
    regions = mapped_regions()
    if regions is None or regions <= limit * fraction:
        return False
    release()
    return True


def release() -> None:
    """Free every compiled program nothing else holds: jax's caches dropped, then a
    collection."""
    jax.clear_caches()
    gc.collect()
