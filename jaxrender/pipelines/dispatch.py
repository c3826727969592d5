"""Work lists and chunked dispatch: the one place where shading work is launched.

A pipeline that shades fewer points must run fewer shader evaluations, and its counts must be
what it launched. The points to shade are compacted into a ``WorkList``
(``compaction.compact_indices``), and ``shade()`` runs over it in launches of static sizes, like
DispatchIndirect: full chunks in a ``lax.while_loop`` whose trip count is the number of full
chunks, then the remainder in halving sizes (``tail_sizes``), never over the full screen with a
mask. The counts are read off that same work list (``count`` items, ``chunks`` launches,
``lanes`` launched).
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
# The smallest launch of a dispatch's tail. Below a few thousand lanes a GPU launch costs its
# latency whatever its size, and each tail size compiles the shader once more; at the smallest
# chunk there is no tail, so small frames compile one copy of the shader.
MIN_TAIL = MIN_CHUNK


def auto_chunk(capacity: int) -> int:
    """The chunk size for a work list of at most ``capacity`` items: the power of two at or above
    capacity / 8, within [2^12, 2^18], so a full screen takes about eight iterations.

    Why not small: every iteration of the dispatch loop costs a fixed launch-and-sync overhead on
    a GPU, which for a full screen in 4096-lane chunks is several times the shading itself.
    Why not the whole list: see ``tail_sizes``: the work that does not fill a chunk is
    launched in smaller pieces, so a pipeline that shades little does not pay for a chunk."""
    want = max(int(capacity) // 8, 1)
    return int(min(max(1 << (want - 1).bit_length(), MIN_CHUNK), MAX_CHUNK))


def resolve_chunk(chunk: int, capacity: int) -> int:
    """``chunk`` as given, or ``auto_chunk(capacity)`` for 0."""
    return int(chunk) if int(chunk) > 0 else auto_chunk(capacity)


def tail_sizes(chunk: int, smallest: int = MIN_TAIL) -> tuple[int, ...]:
    """The launch sizes of a dispatch's tail after its full chunks: chunk / 2, chunk / 4, ...
    down to ``smallest``. Each runs at most once (when the remainder is at least that size), so
    the tail is the remainder's binary expansion and the lanes launched past the work stay under
    ``smallest`` (``2 * smallest`` for a chunk that is not a power of two), not under ``chunk``: shading work follows the items, as a GPU's waves do, at
    the price of compiling the shader once per size. Empty when ``chunk <= smallest``."""
    sizes, s = [], int(chunk) // 2
    while s >= max(int(smallest), 1) and int(chunk) > int(smallest):
        sizes.append(s)
        s //= 2
    return tuple(sizes)


def launch_all(n: Array, chunk: int, launch: Callable, acc, smallest: int = MIN_TAIL):
    """Run ``launch(start, size, acc) -> acc`` over lanes ``0 .. n-1``: full chunks in a loop,
    then the ``tail_sizes`` but the smallest each at most once, then the last lanes in launches
    of the smallest size (at most two; masked: ``launch`` must treat lanes at or past ``n`` as
    not live). Returns
    (acc, launches int32, lanes launched int32)."""
    sizes = tail_sizes(chunk, smallest)
    if not sizes:  # one size: ceil(n / chunk) masked launches
        n_chunks = (n + chunk - 1) // chunk
        acc = jax.lax.fori_loop(0, n_chunks, lambda k, a: launch(k * chunk, chunk, a), acc)
        return acc, n_chunks, n_chunks * chunk
    n_full = n // chunk
    acc = jax.lax.fori_loop(0, n_full, lambda k, a: launch(k * chunk, chunk, a), acc)
    start, launches = n_full * chunk, n_full
    for size in sizes[:-1]:
        take = n - start >= size
        acc = jax.lax.cond(take, lambda a, s0=start, sz=size: launch(s0, sz, a),
                           lambda a: a, acc)
        start, launches = start + jnp.where(take, size, 0), launches + take.astype(jnp.int32)
    last = sizes[-1]
    n_last = (n - start + last - 1) // last
    acc = jax.lax.fori_loop(0, n_last, lambda k, a: launch(start + k * last, last, a), acc)
    return acc, launches + n_last, start + n_last * last


@pytree_dataclass
class WorkList:
    """A compacted work list and, once dispatched, what was launched for it.

    items int32[N]: item indices (pixels, samples, fragments, shadels), the first ``count``
    live; count int32[]: live items. After ``run`` (or ``shade``): ``chunk`` (static lanes of
    the largest launch), ``invocations`` (lanes that wrote a result: ``count``, or fewer for
    lane lists whose lanes are not one-to-one with outputs), ``chunks`` (launches: full chunks
    and the tail's smaller ones) and ``lanes`` (lanes launched, idle ones included).
    """

    items: Array
    count: Array
    invocations: Array | None = None
    chunks: Array | None = None
    lanes: Array | None = None
    chunk: int = static_field(default=0)

    @classmethod
    def of(cls, active: Array) -> "WorkList":
        """The True entries of bool[N] in order (padded with 0) and their count."""
        items, count = compact_indices(active, active.shape[0])
        return cls(items, count)

    @property
    def idle_lanes(self) -> Array:
        return self.lanes - self.invocations

    @property
    def counts(self) -> dict:
        return {"invocations": self.invocations, "lanes": self.lanes, "chunks": self.chunks}


def run(work: WorkList, fn: Callable[[Array, Array], Array], out: Array,
        chunk: int, smallest: int = MIN_TAIL) -> tuple[Array, WorkList]:
    """For the live items of ``work``, write ``fn(items int32[size], live bool[size]) ->
    values[size, ...]`` into ``out[items]``.

    Launches ``launch_all``'s pieces (full chunks, then the tail's smaller sizes); lanes past
    the work are passed live=False and their results are discarded. ``chunk`` 0 picks
    ``auto_chunk`` for the list. Returns (out, the work list with its dispatch counts).
    """
    items, n = work.items, work.count
    chunk = int(min(resolve_chunk(chunk, items.shape[0]), max(items.shape[0], 1)))
    padded = jnp.concatenate([items, jnp.zeros((chunk,), items.dtype)])
    sentinel = out.shape[0]  # out-of-range index: scatter drops the lane

    def launch(start, size, acc):
        lane_items = jax.lax.dynamic_slice(padded, (start,), (size,))
        live = start + jnp.arange(size, dtype=jnp.int32) < n
        vals = fn(lane_items, live)
        return acc.at[jnp.where(live, lane_items, sentinel)].set(vals, mode="drop")

    out, launches, lanes = launch_all(n, chunk, launch, out, smallest)
    return out, WorkList(items, n, n, launches, lanes, chunk)


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
    smallest: int = MIN_TAIL,
) -> tuple[Array, WorkList]:
    """Launch lanes ``0 .. n-1`` as ``launch_all`` does: ``fn(lanes int32[size], live
    bool[size])`` returns ``(dest int32[size], values[size, ...], write bool[size])`` and
    ``out[dest] = values`` where ``live & write``. For work whose lanes are not one-to-one with
    outputs (2x2 quads with helper lanes, waves with idle lanes): every lane is evaluated, only
    some write.

    Returns (out, the lane list as a WorkList: ``count`` n lanes, ``invocations`` the lanes
    that wrote). ``chunk`` 0 picks ``auto_chunk`` for ``out``'s length.
    """
    chunk = resolve_chunk(chunk, out.shape[0])
    sentinel = out.shape[0]

    def launch(start, size, carry):
        acc, wrote = carry
        lanes = start + jnp.arange(size, dtype=jnp.int32)
        live = lanes < n
        dest, vals, write = fn(lanes, live)
        ok = live & write
        acc = acc.at[jnp.where(ok, dest, sentinel)].set(vals, mode="drop")
        return acc, wrote + jnp.sum(ok, dtype=jnp.int32)

    (out, wrote), launches, lanes = launch_all(n, chunk, launch, (out, jnp.int32(0)), smallest)
    return out, WorkList(jnp.zeros((0,), jnp.int32), n, wrote, launches, lanes, chunk)
