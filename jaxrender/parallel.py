"""Batches of frames and sweep points over every local device, with jax.sharding.

Two kinds of parallel work, one helper each:

* ``sharded_map(fn, batched, *rest)``: ``fn(item, *rest)`` for every item of a batch (the
  frames of a camera path, the points of a sweep over a *traced* parameter such as the DACS
  threshold), vmapped, with the batch axis laid over a 1-D mesh of the devices
  (``NamedSharding(mesh, P("batch"))``) and ``rest`` (the scene) replicated. A batch that does
  not divide by the device count is padded by repeating its last item and trimmed afterwards;
  ``chunk`` bounds the items each device holds at once (frames are big: a 1080p pipeline frame
  with its fragment lists is tens of MiB).
  ``render_frames(render, scene, cameras, cfg)`` is this for a pipeline over a camera path.
* ``round_robin(calls)``: programs that cannot share one compiled program (sweeps over
  *static* parameters: resolution, pipeline, capacities) placed one per device in turn; JAX
  dispatches asynchronously, so they run concurrently on different devices.

The same code runs on one device (the CPU included: a 1-device mesh is a no-op sharding) and
on N. ``XLA_FLAGS=--xla_force_host_platform_device_count=N`` gives N CPU devices to try it.

Multi-host use (not run here; what the code needs is already in place)
----------------------------------------------------------------------
On a cluster, start one process per host and call ``jax.distributed.initialize()`` before any
other JAX call (arguments, or the SLURM / Open MPI / Cloud TPU environment, give the
coordinator address, process count and id). ``jax.devices()`` then lists every device of
every host, so ``device_mesh()`` spans the cluster and ``sharded_map`` lays the batch over all
of them; each process must build the same inputs (a camera path is cheap: build it
everywhere from the same study file). ``jax.device_put`` of a host array onto a sharding
with devices of other processes takes each process's addressable shards; for inputs each
host computes on its own use ``jax.make_array_from_process_local_data(batch_sharding(mesh),
local_part)``. Outputs are global arrays whose shards live on their hosts: gather them with
``jax.experimental.multihost_utils.process_allgather`` or have each process write its
``addressable_shards`` (the study store takes one row per frame, so per-host files merge
by concatenation). ``round_robin`` takes ``jax.local_devices()`` in that setting: each
process runs its share of static sweep points, chosen by ``jax.process_index()``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

AXIS = "batch"


def device_mesh(devices: Sequence[jax.Device] | None = None) -> Mesh:
    """A 1-D mesh over ``devices`` (default: every device, all hosts) with axis ``"batch"``."""
    devs = list(devices) if devices is not None else jax.devices()
    return Mesh(np.asarray(devs, dtype=object), (AXIS,))


def batch_sharding(mesh: Mesh) -> NamedSharding:
    """Leading axis split over the mesh, the rest of each array whole."""
    return NamedSharding(mesh, PartitionSpec(AXIS))


def replicated(mesh: Mesh) -> NamedSharding:
    return NamedSharding(mesh, PartitionSpec())


def batch_size(batched) -> int:
    sizes = {int(np.shape(a)[0]) for a in jax.tree_util.tree_leaves(batched)}
    if len(sizes) != 1:
        raise ValueError(f"sharded_map: batched leaves disagree on the leading axis: {sorted(sizes)}")
    return sizes.pop()


def pad_batch(batched, multiple: int):
    """Pad the leading axis to a multiple of ``multiple`` by repeating the last item (a valid
    input, unlike zeros: a zero camera is degenerate). Returns (padded, original size)."""
    n = batch_size(batched)
    pad = -n % multiple
    if pad == 0:
        return batched, n

    def one(a):
        a = jnp.asarray(a)
        return jnp.concatenate([a, jnp.repeat(a[-1:], pad, axis=0)], axis=0)

    return jax.tree_util.tree_map(one, batched), n


def shard_batch(batched, mesh: Mesh, size: int = 0):
    """Pad (to a multiple of the device count, or to ``size`` items) and place a batch on the
    mesh, split along its leading axis. Returns (array, n)."""
    n = batch_size(batched)
    padded, _ = pad_batch(batched, size if 0 < n < size else mesh.size)
    return jax.device_put(padded, batch_sharding(mesh)), n


@functools.lru_cache(maxsize=64)
def _vmapped(fn: Callable, n_rest: int, mesh: Mesh):
    """One jitted program per (fn, arity, mesh): a later call with new values recompiles
    nothing (``fn`` must be the same object: keep it, don't build a lambda per call)."""
    return jax.jit(jax.vmap(fn, in_axes=(0,) + (None,) * n_rest),
                   out_shardings=batch_sharding(mesh))


def sharded_map(fn: Callable, batched, *rest, mesh: Mesh | None = None, chunk: int = 0):
    """``fn(item, *rest)`` for every item along the leading axis of ``batched`` (a pytree),
    vmapped and sharded over ``mesh`` (default: all devices); ``rest`` is replicated.

    ``chunk`` > 0: at most ``chunk`` items per device per call, the batch run in slices of
    ``chunk * devices`` items (bounds memory). Results are stacked like ``jax.vmap``'s."""
    mesh = mesh or device_mesh()
    n = batch_size(batched)
    step = chunk * mesh.size if chunk > 0 else n
    step = -(-step // mesh.size) * mesh.size  # whole items per device
    prog = _vmapped(fn, len(rest), mesh)
    rest = jax.device_put(rest, replicated(mesh))
    outs = []
    for start in range(0, n, step):
        part = jax.tree_util.tree_map(lambda a, s=start: a[s:s + step], batched)
        xs, m = shard_batch(part, mesh, size=step)  # the last slice too: one compile
        out = prog(xs, *rest)
        outs.append(jax.tree_util.tree_map(lambda a, m=m: a[:m], out))
    if len(outs) == 1:
        return outs[0]
    return jax.tree_util.tree_map(lambda *a: jnp.concatenate(a, axis=0), *outs)


@functools.lru_cache(maxsize=64)
def _render_item(render: Callable, cfg):
    """``camera, scene -> Frame`` for one static config, cached so that its identity (and so
    the compiled program) is stable across calls."""
    def item(camera, scene):
        return render(scene, camera, cfg)

    return item


def render_frames(render: Callable, scene, cameras, cfg, *, mesh: Mesh | None = None,
                  chunk: int = 0):
    """Every frame of a batched camera (``CameraPath.cameras``: arrays with a leading T axis)
    through ``render(scene, camera, cfg)``, vmapped and sharded over the devices.
    Returns a Frame whose arrays have a leading T axis."""
    return sharded_map(_render_item(render, cfg), cameras, scene, mesh=mesh, chunk=chunk)


def round_robin(calls: Sequence[tuple[Callable, tuple]],
                devices: Sequence[jax.Device] | None = None) -> list:
    """Run ``fn(*args)`` for each (fn, args), call i on device i mod N, all dispatched before
    any is waited for. For sweeps over static parameters (one program per point)."""
    devs = list(devices) if devices is not None else jax.local_devices()
    outs = []
    for i, (fn, args) in enumerate(calls):
        dev = devs[i % len(devs)]
        with jax.default_device(dev):
            outs.append(fn(*jax.device_put(args, dev)))
    return [jax.block_until_ready(o) for o in outs]
