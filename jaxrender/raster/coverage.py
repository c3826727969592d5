"""Coverage by fixed-capacity work lists: every triangle's pixel bounding box is expanded into
(pixel, triangle) work items by a prefix sum, and the items are tested in chunks of a static
capacity inside a ``lax.while_loop``. However many items a frame needs, all are processed: the
capacity sets the chunk size (memory and compile shape), never what is kept.

Triangles arrive by reference (``Triangles``: vertices, an index and a mask) with the function
that sets them up; each traversal decides where the setup happens. The stored traversals set up
every triangle once and gather the results per item; "recompute" (the GPU's) keeps only each
triangle's item count and sets up again per item from its three vertices: on an H100 writing
and gathering ~130 bytes of setup per triangle cost more than the arithmetic (2.6M triangles at
1080p, 2026-11-23). Setup is a pure function of the vertices, so every traversal gets the same
bits.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

from jaxrender.raster.setup import SUBPIXEL, SetupFn, TriSetup
from jaxrender.types import Array, pytree_dataclass

EMPTY_KEY = (1 << 63) - 1  # no fragment: larger than every packed key
SAFE_VERTEX = (0.0, 0.0, 0.0, 1.0)  # stands in for a masked slot's vertices; never covers


@pytree_dataclass
class Triangles:
    """Triangle slots by reference: slot s has the clip-space vertices ``verts[index[s]]``
    (float32[V, 4], int32[N, 3]), covers pixels only where ``ok[s]`` (bool[N]) and carries the
    triangle id ``tri[s]`` (int32[N])."""

    verts: Array
    index: Array
    ok: Array
    tri: Array

    def gather(self, slots: Array | None = None) -> tuple[Array, Array, Array]:
        """(clip float32[n, 3, 4], ok, tri) of ``slots`` (every slot for None); a masked
        slot's vertices are replaced by SAFE_VERTEX, so nothing downstream sees NaN or Inf."""
        pick = (lambda a: a) if slots is None else (lambda a: a[slots])
        ok = pick(self.ok)
        tc = self.verts[pick(self.index)]
        safe = jnp.asarray(SAFE_VERTEX, tc.dtype)
        return jnp.where(ok[:, None, None], tc, safe), ok, pick(self.tri)


@pytree_dataclass
class WorkChunk:
    """One chunk of work items; arrays of shape [capacity]."""

    slot: Array  # int32 triangle slot in the setup arrays
    tri: Array  # int32 original triangle id
    px: Array  # int32 pixel column
    py: Array  # int32 pixel row
    covered: Array  # bool: live item whose sample point is inside the triangle
    depth: Array  # float32 window depth at the sample point (clamped to [0, 1])


def total_items(setup: TriSetup) -> Array:
    return jnp.sum(setup.count)


def running_max(x: Array) -> Array:
    """Inclusive running maximum. Measured (2026-11-22): on an H100 lax.cummax took 0.28 ms
    for 4M int32 where an associative scan took 1.34 ms; on a 2-core CPU the associative scan
    is several times faster. The choice is made when the program is lowered for a platform."""
    return jax.lax.platform_dependent(
        x,
        cpu=lambda a: jax.lax.associative_scan(jnp.maximum, a),
        default=jax.lax.cummax,
    )


def owners(count: Array, incl: Array, base: Array, capacity: int):
    """Expand runs of ``count[s]`` items per slot s (``incl`` = inclusive cumsum of count) and
    return, for the items [base, base + capacity): the owning slot (int32), the item's index
    inside its run (int32) and whether the item exists."""
    n_slots = count.shape[0]
    count = count.astype(incl.dtype)
    starts = incl - count
    # Which slot owns each item: mark each slot's first item, then a running maximum.
    local = starts - base
    in_chunk = (count > 0) & (local >= 0) & (local < capacity)
    mark = jnp.full((capacity,), -1, jnp.int32)
    mark = mark.at[jnp.where(in_chunk, local, capacity)].max(
        jnp.arange(n_slots, dtype=jnp.int32), mode="drop"
    )
    # The triangle owning item `base`: searchsorted(incl, base, side="right"), as one reduction
    # (jnp.searchsorted's default is a loop of ~20 tiny kernels on a GPU).
    first = jnp.sum(incl <= base, dtype=jnp.int32)
    mark = mark.at[0].max(first)
    slot = jnp.minimum(running_max(mark), n_slots - 1)
    # Index inside the run; fits int32 (a run has < 2^31 items).
    local32 = jnp.clip(local, -(2**31) + 1, 2**31 - 1).astype(jnp.int32)
    j = jnp.arange(capacity, dtype=jnp.int32) - local32[slot]
    live = base + jnp.arange(capacity, dtype=jnp.int64) < incl[-1]
    return slot, j, live


def window_depth(e: list, z: list, inv_area: Array) -> Array:
    """Window depth from the three exact edge values (float64) of a sample, shared by every
    traversal so that all give the same bits. The sum is written out, not a reduction over
    an axis of 3: XLA CPU hands such a reduction to a library call (measured 2026-11-22 on a
    2-core CPU: 11.7 of 53 ms at 640x360 for this sum alone)."""
    lam = [ei.astype(jnp.float32) * inv_area for ei in e]
    # A constant-depth triangle takes its vertex depth exactly: float32 barycentrics need not
    # sum to 1, and rounding must not decide between coplanar triangles (the id does).
    flat = (z[0] == z[1]) & (z[1] == z[2])
    # The products of float32 factors are exact in float64, so a compiler that contracts a
    # multiply and an add into an FMA (XLA's CPU and GPU backends do, fusion by fusion) gets the
    # same bits as one that does not: every program that rasterizes (VisBuffer, fragment list)
    # computes the same depth for the same sample.
    wide = [lam[i].astype(jnp.float64) * z[i].astype(jnp.float64) for i in range(3)]
    depth = jnp.where(flat, z[0], (wide[0] + wide[1] + wide[2]).astype(jnp.float32))
    return jnp.clip(depth, 0.0, 1.0)


def _chunk(setup: TriSetup, incl: Array, base: Array, capacity: int, offset: Array) -> WorkChunk:
    slot, j, live = owners(setup.count, incl, base, capacity)
    return _items(jax.tree_util.tree_map(lambda a: a[slot], setup), slot, j, live, offset)


def _items(su: TriSetup, slot: Array, j: Array, live: Array, offset: Array) -> WorkChunk:
    """Work items from the setup of each item's own triangle (arrays of shape [capacity])."""
    bw = su.bw
    row = jnp.floor((j.astype(jnp.float64) + 0.5) / bw.astype(jnp.float64)).astype(jnp.int32)
    px = su.x0 + (j - row * bw)
    py = su.y0 + row
    sx = (px * SUBPIXEL).astype(jnp.float64) + offset[0].astype(jnp.float64)
    sy = (py * SUBPIXEL).astype(jnp.float64) + offset[1].astype(jnp.float64)
    e = su.edge_a * sx[:, None] + su.edge_b * sy[:, None] + su.edge_c
    covered = live & jnp.all(e + su.top_left > 0, axis=1)
    z = su.z
    depth = window_depth([e[:, i] for i in range(3)], [z[:, i] for i in range(3)], su.inv_area)
    return WorkChunk(slot, su.tri, px, py, covered, depth)


TRAVERSALS = ("bbox", "spans", "recompute")


def for_each_chunk(
    tris: Triangles, setup: SetupFn, capacity: int, offset: Array, state,
    fn: Callable[[object, WorkChunk], object], traversal: str, peel: bool = False,
    then: tuple | None = None,
):
    """Run ``state = fn(state, chunk)`` over the work items of ``tris``, in chunks (dynamic
    trip count); returns (state, items: bounding-box pixels of the triangles). Every traversal
    hands ``fn`` the same covered items in the same order with the same values (the box
    traversals also hand it uncovered items, masked by ``covered``). ``traversal``: "bbox"
    (every bounding-box pixel is an item, tested by the edge functions; setup stored),
    "recompute" (the same items, setup recomputed per item) or "spans" (exact per-row spans;
    see ``spans.py``); ``raster.rasterize.traverse`` picks one per platform. ``peel``: the box
    traversals run their first chunk outside the loop and join ``then`` into it (see
    ``_chunk_loop``). ``then``: more work after the chunks, (n: int64 scalar, body(k, (state,
    items)) -> (state, items)) for k in [0, n); its items are added to the count. ``spans`` is
    imported here because it builds on this module."""
    if traversal not in TRAVERSALS:
        raise ValueError(f"traversal must be one of {TRAVERSALS}, got {traversal!r}")
    if traversal == "recompute":
        return _for_each_recompute_chunk(tris, setup, capacity, offset, state, fn, peel, then)
    su = setup(*tris.gather(), offset)
    if traversal == "spans":
        from jaxrender.raster.spans import for_each_span_chunk

        state = for_each_span_chunk(su, capacity, offset, state, fn)
        return _then_loop(then, state, jnp.sum(su.count))
    return _for_each_bbox_chunk(su, capacity, offset, state, fn, peel, then)


def _then_loop(then, state, items):
    """``then``'s steps as a loop of their own (the traversals that do not peel)."""
    if then is None:
        return state, items
    n, body = then
    return jax.lax.fori_loop(jnp.int64(0), n, body, (state, items))


def _chunk_loop(total: Array, capacity: int, state, body, peel: bool, then):
    """``state = body(k, state)`` for the chunks k of ``total`` items, then ``then``; returns
    (state, total + the items ``then`` adds). A loop with a dynamic trip count makes the GPU
    wait for the host at every test of its condition. ``peel`` runs chunk 0 unconditionally
    (its items are masked when there are none) and runs the further chunks and ``then``'s
    steps in one loop, choosing per step, so that a frame whose items fit one chunk and which
    has no ``then`` work tests one condition instead of two or three."""
    n_chunks = (total + capacity - 1) // capacity
    if not peel:
        state = jax.lax.fori_loop(jnp.int64(0), n_chunks, body, state)
        return _then_loop(then, state, total)
    state = body(jnp.int64(0), state)
    n_more = jnp.maximum(n_chunks, 1)
    if then is None:
        return jax.lax.fori_loop(jnp.int64(1), n_more, body, state), total
    n_then, then_body = then

    def step(k, carry):
        return jax.lax.cond(k < n_more, lambda: (body(k, carry[0]), carry[1]),
                            lambda: then_body(k - n_more, carry))

    return jax.lax.fori_loop(jnp.int64(1), n_more + n_then, step, (state, total))


def _for_each_bbox_chunk(setup: TriSetup, capacity: int, offset: Array, state, fn,
                         peel: bool = False, then=None):
    incl = jnp.cumsum(setup.count)
    total = incl[-1]

    def body(i, st):
        return fn(st, _chunk(setup, incl, i * capacity, capacity, offset))

    return _chunk_loop(total, capacity, state, body, peel, then)


def _for_each_recompute_chunk(tris: Triangles, setup: SetupFn, capacity: int, offset: Array,
                              state, fn, peel: bool = False, then=None):
    # Per triangle: the snapped vertices (the divisions and the vertex gathers, done once) and
    # the item count; per item: the rest of the setup from its triangle's snapped vertices.
    tri_clip, ok, tri = tris.gather()
    snapped = setup.snap(tri_clip)
    count = setup.from_snapped(*snapped, ok, tri, offset).count
    incl = jnp.cumsum(count)
    total = incl[-1]

    def body(i, st):
        slot, j, live = owners(count, incl, i * capacity, capacity)
        su = setup.from_snapped(*(a[slot] for a in snapped), ok[slot], tri[slot], offset)
        return fn(st, _items(su, slot, j, live, offset))

    return _chunk_loop(total, capacity, state, body, peel, then)


def depth_key(depth: Array, tri: Array) -> Array:
    """Pack (depth, id) into one int64 whose minimum is the nearest, lowest-id fragment.

    Non-negative float32 bit patterns order like the floats, so depth sorts first and ties go
    to the lower triangle index."""
    bits = jax.lax.bitcast_convert_type(depth, jnp.int32).astype(jnp.int64)
    return (bits << 32) | tri.astype(jnp.int64)
