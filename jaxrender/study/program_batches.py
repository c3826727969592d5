"""A study's sequences in batches whose programs a process can hold at once.

XLA:CPU maps a few memory regions for every kernel of a program it loads and unmaps them only
when the executable is freed: about a thousand for one pipeline program (RESULTS.md, twelfth
session). Linux caps a process's mappings at ``vm.max_map_count`` (65,530 by default), and
when XLA's next mmap fails past it, the process segfaults inside the compiler. A study that
compiled all its programs first would pass that limit on the CPU from about 60 programs
(pipelines_overview compiles 162). So on the CPU backend the runner compiles, renders and frees one batch of sequences at a time, each
batch holding at most ``programs_at_once()`` programs; sequences that share a program stay in
one batch. Elsewhere (a GPU's kernels live on the device) every sequence is one batch.
"""

from __future__ import annotations

from pathlib import Path

import jax

# Regions one program may map, with room to spare (forward, the largest measured, maps 1,300).
REGIONS_PER_PROGRAM = 2000
MAP_COUNT_FILE = Path("/proc/sys/vm/max_map_count")


def programs_at_once() -> int | None:
    """How many compiled programs this process holds at once: None for no bound (not the
    CPU backend, or no readable map limit); else enough to fill half the map limit."""
    if jax.default_backend() != "cpu":
        return None
    try:
        limit = int(MAP_COUNT_FILE.read_text())
    except (OSError, ValueError):
        return None
    return max(1, limit // 2 // REGIONS_PER_PROGRAM)


def batches(todo: list, programs_of, most: int | None) -> list[list]:
    """``todo``'s items in order-keeping batches of at most ``most`` distinct programs (None:
    one batch). ``programs_of(item)`` is the set of program identities an item runs; items
    that share one are kept in one batch, so no program compiles twice. A group larger than
    ``most`` is a batch of its own."""
    if most is None or not todo:
        return [list(todo)] if todo else []
    groups: list[tuple[set, list]] = []
    for item in todo:  # union the items that share a program
        progs = set(programs_of(item))
        joined = [g for g in groups if g[0] & progs]
        for g in joined:
            groups.remove(g)
            progs |= g[0]
        items = [i for g in joined for i in g[1]] + [item]
        groups.append((progs, items))
    out: list[list] = []
    held: set = set()
    for progs, items in groups:
        if out and len(held | progs) <= most:
            out[-1].extend(items)
            held |= progs
        else:
            out.append(list(items))
            held = set(progs)
    order = {id(item): i for i, item in enumerate(todo)}
    return [sorted(b, key=lambda item: order[id(item)]) for b in out]


def release_programs() -> None:
    """Free every compiled program nothing else holds: jax's caches and a collection."""
    import gc

    jax.clear_caches()
    gc.collect()
