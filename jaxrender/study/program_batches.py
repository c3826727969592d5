"""A study's sequences in batches whose programs a process can hold at once.

XLA:CPU keeps about a thousand memory mappings for each loaded pipeline program, against the
process's limit of ``vm.max_map_count`` (``jaxrender.memory_maps``). A study that compiled all
its programs first and held them would pass that limit on the CPU from about 60 programs
(pipelines_overview compiles 162). So on the CPU backend the runner compiles, renders and
frees one batch of sequences at a time, each batch holding at most ``programs_at_once()``
programs; sequences that share a program stay in one batch. Elsewhere (a GPU's kernels live on
the device) every sequence is one batch.
"""

from __future__ import annotations

import jax

from jaxrender import memory_maps

# Regions one program may map, with room to spare (forward, the largest measured, maps 1,300).
REGIONS_PER_PROGRAM = 2000


def programs_at_once() -> int | None:
    """How many compiled programs this process holds at once: None for no bound (not the
    CPU backend, or no readable map limit); else enough to fill half the map limit."""
    limit = memory_maps.map_limit()
    if jax.default_backend() != "cpu" or limit is None:
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
