"""Coverage by fixed-capacity work lists: every triangle's pixel bounding box is expanded into
(pixel, triangle) work items by a prefix sum, and the items are tested in chunks of a static
capacity inside a ``lax.while_loop``. However many items a frame needs, all are processed: the
capacity sets the chunk size (memory and compile shape), never what is kept.

Triangles arrive by reference (``Triangles``: vertices, an index and a mask) with the function
that sets them up; each traversal decides where the setup happens. The stored traversals set up
every triangle once and gather the results per item; "recompute" (the GPU's) keeps only each
triangle's item count and sets up again per item from its three vertices: on a GPU writing
and gathering ~130 bytes of setup per triangle costs more than the arithmetic when triangles
are dense. Setup is a pure function of the vertices, so every traversal gets the same
bits.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

from jaxrender.raster.setup import SetupFn, TriSetup
from jaxrender.raster.spans import for_each_span_chunk
from jaxrender.raster.work_items import (Triangles, WorkChunk, chunk_items, items_from_setup,
                                         owners)
from jaxrender.types import Array

TRAVERSALS = ("bbox", "spans", "recompute")
PEELS = (False, True, "first")


def for_each_chunk(
    tris: Triangles, setup: SetupFn, capacity: int, offset: Array, state,
    fn: Callable[[object, WorkChunk], object], traversal: str, peel: bool | str = False,
    then: tuple | None = None,
):
    """Run ``state = fn(state, chunk)`` over the work items of ``tris``, in chunks (dynamic
    trip count); returns (state, items: bounding-box pixels of the triangles). Every traversal
    hands ``fn`` the same covered items in the same order with the same values (the box
    traversals also hand it uncovered items, masked by ``covered``). ``traversal``: "bbox"
    (every bounding-box pixel is an item, tested by the edge functions; setup stored),
    "recompute" (the same items, setup recomputed per item) or "spans" (exact per-row spans;
    see ``spans.py``); ``raster.rasterize.traverse`` picks one per platform. ``peel`` (one of
    PEELS): the box traversals run their first chunk outside the loop and join ``then`` into
    it (True), or run ``then`` in a loop of its own ("first"; see ``_chunk_loop``). ``then``:
    more work after the chunks, (n: int64 scalar, body(k, (state, items)) -> (state, items))
    for k in [0, n); its items are added to the count."""
    if traversal not in TRAVERSALS:
        raise ValueError(f"traversal must be one of {TRAVERSALS}, got {traversal!r}")
    if peel not in PEELS:
        raise ValueError(f"peel must be one of {PEELS}, got {peel!r}")
    if traversal == "recompute":
        return _for_each_recompute_chunk(tris, setup, capacity, offset, state, fn, peel, then)
    su = setup(*tris.gather(), offset)
    if traversal == "spans":
        state = for_each_span_chunk(su, capacity, offset, state, fn)
        return _then_loop(then, state, jnp.sum(su.count))
    return _for_each_bbox_chunk(su, capacity, offset, state, fn, peel, then)


def _then_loop(then, state, items):
    """``then``'s steps as a loop of their own (the traversals that do not peel)."""
    if then is None:
        return state, items
    n, body = then
    return jax.lax.fori_loop(jnp.int64(0), n, body, (state, items))


def _chunk_loop(total: Array, capacity: int, state, body, peel: bool | str, then):
    """``state = body(k, state)`` for the chunks k of ``total`` items, then ``then``; returns
    (state, total + the items ``then`` adds). A loop with a dynamic trip count makes the GPU
    wait for the host at every test of its condition. ``peel`` runs chunk 0 unconditionally
    (its items are masked when there are none) and runs the further chunks and ``then``'s
    steps in one loop, choosing per step, so that a frame whose items fit one chunk and which
    has no ``then`` work tests one condition instead of two or three. ``peel="first"`` runs
    chunk 0 unconditionally and ``then`` in a loop of its own: one condition fewer than no
    peel, and no conditional inside the loop, through which XLA would copy the state at every
    step (a fragment list's capacity-sized arrays)."""
    n_chunks = (total + capacity - 1) // capacity
    if not peel:
        state = jax.lax.fori_loop(jnp.int64(0), n_chunks, body, state)
        return _then_loop(then, state, total)
    state = body(jnp.int64(0), state)
    n_more = jnp.maximum(n_chunks, 1)
    if then is None or peel == "first":
        return _then_loop(then, jax.lax.fori_loop(jnp.int64(1), n_more, body, state), total)
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
        return fn(st, chunk_items(setup, incl, i * capacity, capacity, offset))

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
        return fn(st, items_from_setup(su, slot, j, live, offset))

    return _chunk_loop(total, capacity, state, body, peel, then)
