"""Work lists and chunked dispatch: the one place where shading work is launched.

A pipeline that shades fewer points must run fewer shader evaluations, or its time would not
follow its work and a comparison of architectures would measure the simulation. The points to shade are compacted into a ``WorkList`` (``compaction.compact_indices``), and
``shade()`` runs over it in chunks of a static size inside a ``lax.while_loop`` whose trip count
is the number of chunks that hold work, like DispatchIndirect: the compiled program evaluates
the shader ``ceil(n / chunk)`` times, never over the full screen with a mask. The counts are
read off that same work list, so they cannot disagree with the work done (``count`` items, ``chunks * chunk`` lanes launched).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.types import Array, pytree_dataclass, static_field

DEFAULT_CHUNK = 0  # auto: see auto_chunk
MIN_CHUNK, MAX_CHUNK = 1 << 12, 1 << 18


def auto_chunk(capacity: int) -> int:
    """The chunk size for a work list of at most ``capacity`` items: the power of two at or above
    capacity / 16, within [2^12, 2^18], so a full screen takes about sixteen iterations.

    Why not small: every iteration of the dispatch loop costs a fixed launch-and-sync overhead on
    a GPU, which for a full screen in 4096-lane chunks is several times the shading itself.
    Why not the whole list: the last chunk's idle lanes are launched too (and counted in
    ``lanes``), so a pipeline that shades little must not pay for a full screen; at a sixteenth
    the idle lanes of a half-screen list stay a few percent of its work (an eighth launched 38%
    more lanes than checkerboard shades at 1920x1080, and its time followed the lanes)."""
    want = max(int(capacity) // 16, 1)
    return int(min(max(1 << (want - 1).bit_length(), MIN_CHUNK), MAX_CHUNK))


def resolve_chunk(chunk: int, capacity: int) -> int:
    """``chunk`` as given, or ``auto_chunk(capacity)`` for 0."""
    return int(chunk) if int(chunk) > 0 else auto_chunk(capacity)


@pytree_dataclass
class WorkList:
    """A compacted work list and, once dispatched, what was launched for it.

    items int32[N]: item indices (pixels, samples, fragments, shadels), the first ``count``
    live; count int32[]: live items. After ``run`` (or ``shade``): ``chunk`` (static lanes per
    chunk) and ``invocations`` (lanes that wrote a result: ``count``, or fewer for lane lists
    whose lanes are not one-to-one with outputs). ``chunks``, ``lanes`` and ``idle_lanes``
    follow from them.
    """

    items: Array
    count: Array
    invocations: Array | None = None
    chunk: int = static_field(default=0)

    @classmethod
    def of(cls, active: Array) -> "WorkList":
        """The True entries of bool[N] in order (padded with 0) and their count."""
        items, count = compact_indices(active, active.shape[0])
        return cls(items, count)

    @property
    def chunks(self) -> Array:
        return (self.count + self.chunk - 1) // self.chunk

    @property
    def lanes(self) -> Array:
        """Lanes launched: whole chunks, the last one's idle lanes included."""
        return self.chunks * self.chunk

    @property
    def idle_lanes(self) -> Array:
        return self.lanes - self.invocations

    @property
    def counts(self) -> dict:
        return {"invocations": self.invocations, "lanes": self.lanes, "chunks": self.chunks}


def run(work: WorkList, fn: Callable[[Array, Array], Array], out: Array,
        chunk: int) -> tuple[Array, WorkList]:
    """For the live items of ``work``, write ``fn(items int32[chunk], live bool[chunk]) ->
    values[chunk, ...]`` into ``out[items]``.

    Runs ceil(count / chunk) iterations; padding lanes of the last chunk are passed live=False
    and their results are discarded. ``chunk`` 0 picks ``auto_chunk`` for the list. Returns
    (out, the work list with its dispatch counts).
    """
    items, n = work.items, work.count
    chunk = int(min(resolve_chunk(chunk, items.shape[0]), max(items.shape[0], 1)))
    padded = jnp.concatenate([items, jnp.zeros((chunk,), items.dtype)])
    n_chunks = (n + chunk - 1) // chunk
    sentinel = out.shape[0]  # out-of-range index: scatter drops the lane

    def body(k, acc):
        start = k * chunk
        lane_items = jax.lax.dynamic_slice(padded, (start,), (chunk,))
        live = start + jnp.arange(chunk, dtype=jnp.int32) < n
        vals = fn(lane_items, live)
        return acc.at[jnp.where(live, lane_items, sentinel)].set(vals, mode="drop")

    out = jax.lax.fori_loop(0, n_chunks, body, out)
    return out, WorkList(items, n, n, chunk)


def shade(
    work: WorkList,
    points_of: Callable[[Array], object],
    shade_fn: Callable[[object], Array],
    out: Array,
    chunk: int = DEFAULT_CHUNK,
) -> tuple[Array, WorkList]:
    """Shade the items of ``work`` and write their colours (or any per-point result) into
    ``out[items]``; other entries keep their value.

    ``points_of(items)`` builds the SurfacePoints of the given flat indices (gathering from the
    visibility buffer, a G-buffer, a fragment list); ``shade_fn(points)`` is the shared shader
    (or the alpha test). Returns (out, the work list with its dispatch counts).
    """

    def fn(items, live):
        pts = points_of(items)
        pts = dataclasses.replace(pts, valid=pts.valid & live)
        return shade_fn(pts)

    return run(work, fn, out, chunk)


def dispatch_lanes(
    n: Array,
    fn: Callable[[Array, Array], tuple[Array, Array, Array]],
    out: Array,
    chunk: int = DEFAULT_CHUNK,
) -> tuple[Array, WorkList]:
    """Launch lanes ``0 .. n-1`` in chunks: ``fn(lanes int32[chunk], live bool[chunk])`` returns
    ``(dest int32[chunk], values[chunk, ...], write bool[chunk])`` and ``out[dest] = values``
    where ``live & write``. For work whose lanes are not one-to-one with outputs (2x2 quads with
    helper lanes, waves with idle lanes): every lane is evaluated, only some write.

    Returns (out, the lane list as a WorkList: ``count`` n lanes, ``invocations`` the lanes
    that wrote). ``chunk`` 0 picks ``auto_chunk`` for ``out``'s length.
    """
    chunk = resolve_chunk(chunk, out.shape[0])
    n_chunks = (n + chunk - 1) // chunk
    sentinel = out.shape[0]

    def body(k, carry):
        acc, wrote = carry
        lanes = k * chunk + jnp.arange(chunk, dtype=jnp.int32)
        live = lanes < n
        dest, vals, write = fn(lanes, live)
        ok = live & write
        acc = acc.at[jnp.where(ok, dest, sentinel)].set(vals, mode="drop")
        return acc, wrote + jnp.sum(ok, dtype=jnp.int32)

    out, wrote = jax.lax.fori_loop(0, n_chunks, body, (out, jnp.int32(0)))
    return out, WorkList(jnp.zeros((0,), jnp.int32), n, wrote, chunk)
