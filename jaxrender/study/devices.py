"""Where a study's independent work runs: its (scene, pipeline variant) groups spread over the
local devices, and over hosts when JAX's distributed runtime is initialized.

A group is every sequence of one scene and one variant (all its camera paths, each with the
programs of ``programs.roles``): one device compiles and runs all of it, so a variant's
programs compile once. Groups go to devices greedily by rendered frames, heaviest first, ties
by name: the assignment depends on the study only, so a rerun (resuming) puts a group where it
ran before. Over several processes (``jax.distributed.initialize()``, one process per host)
each process takes the groups whose position in that order is its index modulo the process
count, and spreads them over its own devices.

A device's sequences render one after another in a thread of its own: a JAX call releases
the GIL while its device works, so N devices render N sequences at once. Their times are then
measured while the others run (the host is shared), which a row's ``devices`` column says.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax

from jaxrender.errors import UserError


@dataclass(frozen=True)
class Placement:
    """The devices of this process, and which group goes to which (index into ``devices``)."""

    devices: tuple
    group_device: dict  # group key -> index into devices; groups of other processes absent

    def device_of(self, group) -> int | None:
        """Index of the group's device, or None when another process renders it."""
        return self.group_device.get(group)


def select_devices(count: int | None) -> tuple:
    """The first ``count`` local devices (None: all of them); a count out of range is refused,
    naming ``--devices`` and the devices there are."""
    local = tuple(jax.local_devices())
    if count is None:
        return local
    if not 1 <= int(count) <= len(local):
        kinds = ", ".join(sorted({d.device_kind for d in local}))
        raise UserError(f"--devices {count}: this process has {len(local)} local device(s) "
                        f"({kinds}); ask for 1 to {len(local)}")
    return local[: int(count)]


def process_share(groups: dict, index: int, count: int) -> list:
    """The groups (keys of ``groups``: key -> rendered frames) process ``index`` of ``count``
    renders, heaviest first: every ``count``-th of the study's order from position ``index``."""
    order = sorted(groups, key=lambda g: (-groups[g], repr(g)))
    return order[index::count]


def assign(groups: dict, n_devices: int) -> dict:
    """Group key -> device index: each group (heaviest first, ties by name) to the device with
    the fewest frames so far (the lowest index on ties)."""
    load = [0] * n_devices
    out = {}
    for g in sorted(groups, key=lambda g: (-groups[g], repr(g))):
        d = min(range(n_devices), key=lambda i: (load[i], i))
        out[g] = d
        load[d] += groups[g]
    return out


def place(groups: dict, devices: tuple) -> Placement:
    """This process's share of ``groups`` spread over ``devices``."""
    mine = process_share(groups, jax.process_index(), jax.process_count())
    return Placement(tuple(devices), assign({g: groups[g] for g in mine}, len(devices)))


def initialize_distributed(coordinator: str | None = None, num_processes: int | None = None,
                           process_id: int | None = None) -> None:
    """``jax.distributed.initialize`` (one process per host): with no arguments it reads the
    cluster's environment (SLURM, Open MPI, Kubernetes, ...), else the given coordinator
    ``host:port``, process count and this process's id. CPU processes synchronise over Gloo
    (GPU ones over NCCL, whatever this says)."""
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator_address=coordinator, num_processes=num_processes,
                               process_id=process_id)


def wait_for_all_processes(what: str) -> None:
    """A barrier over every process of the distributed runtime (a no-op with one)."""
    if jax.process_count() > 1:
        from jax.experimental import multihost_utils

        multihost_utils.sync_global_devices(f"jaxrender study: {what}")


__all__ = ["Placement", "assign", "initialize_distributed", "place", "process_share",
           "select_devices", "wait_for_all_processes"]
