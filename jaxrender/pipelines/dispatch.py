"""Work lists and chunked dispatch: the one place where shading work is launched.

DESIGN principle 2: a pipeline that shades fewer points must run fewer shader evaluations.
The points to shade are compacted into a work list (``compaction.compact_indices``), and ``shade()`` runs
over it in chunks of a static size inside a ``lax.while_loop`` whose trip count is the number
of chunks that hold work, like DispatchIndirect: the compiled program evaluates the shader
``ceil(n / chunk)`` times, never over the full screen with a mask. Principle 3: the counts
returned are read off that same work list (``n`` points, ``chunks * chunk`` lanes launched).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.types import Array

DEFAULT_CHUNK = 0  # auto: see auto_chunk
MIN_CHUNK, MAX_CHUNK = 1 << 12, 1 << 18


def auto_chunk(capacity: int) -> int:
    """The chunk size for a work list of at most ``capacity`` items: the power of two at or above
    capacity / 8, within [2^12, 2^18], so a full screen takes about eight iterations.

    Why not small: every iteration of the dispatch loop costs a fixed launch-and-sync overhead on
    a GPU; measured on an H100 (2026-11-22, 1080p, 1.28M shaded pixels, deferred) 12.7 ms with
    4096-lane chunks (313 iterations), 3.0 ms with 65536, 2.6 ms with 262144. Why not the whole
    list: the last chunk's idle lanes are launched too (and counted in ``lanes``), so a pipeline
    that shades little must not pay for a full screen."""
    want = max(int(capacity) // 8, 1)
    return int(min(max(1 << (want - 1).bit_length(), MIN_CHUNK), MAX_CHUNK))


def resolve_chunk(chunk: int, capacity: int) -> int:
    """``chunk`` as given, or ``auto_chunk(capacity)`` for 0."""
    return int(chunk) if int(chunk) > 0 else auto_chunk(capacity)


def compact(active: Array) -> tuple[Array, Array]:
    """Indices of the True entries of bool[N] in order, padded with 0, and their count."""
    return compact_indices(active, active.shape[0])


def dispatch(
    work: Array, n: Array, fn: Callable[[Array, Array], Array], out: Array, chunk: int
) -> tuple[Array, dict]:
    """For the first ``n`` entries of the work list ``work`` (int32[N] item indices), write
    ``fn(items int32[chunk], live bool[chunk]) -> values[chunk, ...]`` into ``out[items]``.

    Runs ceil(n / chunk) iterations; padding lanes of the last chunk are passed live=False and
    their results are discarded. ``chunk`` 0 picks ``auto_chunk`` for the list. Returns (out, counts) with ``invocations`` (= n, the live
    lanes), ``lanes`` (chunks x chunk launched) and ``chunks``.
    """
    chunk = int(min(resolve_chunk(chunk, work.shape[0]), max(work.shape[0], 1)))
    padded = jnp.concatenate([work, jnp.zeros((chunk,), work.dtype)])
    n_chunks = (n + chunk - 1) // chunk
    sentinel = out.shape[0]  # out-of-range index: scatter drops the lane

    def body(k, acc):
        start = k * chunk
        items = jax.lax.dynamic_slice(padded, (start,), (chunk,))
        live = start + jnp.arange(chunk, dtype=jnp.int32) < n
        vals = fn(items, live)
        return acc.at[jnp.where(live, items, sentinel)].set(vals, mode="drop")

    out = jax.lax.fori_loop(0, n_chunks, body, out)
    counts = {"invocations": n, "lanes": n_chunks * chunk, "chunks": n_chunks}
    return out, counts


def shade_pixels(
    active: Array,
    points_of: Callable[[Array], object],
    shade_fn: Callable[[object], Array],
    out: Array,
    chunk: int = DEFAULT_CHUNK,
) -> tuple[Array, dict]:
    """Shade the pixels (or samples) flagged in bool[N] and write their colours into out[N, 3].

    ``points_of(items)`` builds the SurfacePoints of the given flat indices (gathering from the
    visibility buffer); ``shade_fn(points)`` is the shared shader. Unflagged entries keep their
    value in ``out``.
    """
    work, n = compact(active)

    def fn(items, live):
        pts = points_of(items)
        pts = dataclasses.replace(pts, valid=pts.valid & live)
        return shade_fn(pts)

    return dispatch(work, n, fn, out, chunk)


def dispatch_lanes(
    n: Array,
    fn: Callable[[Array, Array], tuple[Array, Array, Array]],
    out: Array,
    chunk: int = DEFAULT_CHUNK,
) -> tuple[Array, dict]:
    """Launch lanes ``0 .. n-1`` in chunks: ``fn(lanes int32[chunk], live bool[chunk])`` returns
    ``(dest int32[chunk], values[chunk, ...], write bool[chunk])`` and ``out[dest] = values``
    where ``live & write``. For work whose lanes are not one-to-one with outputs (2x2 quads with
    helper lanes, waves with idle lanes): every lane is evaluated, only some write.

    Returns (out, counts) with ``invocations`` (lanes that wrote), ``lanes`` (chunks x chunk
    launched) and ``chunks``. ``chunk`` 0 picks ``auto_chunk`` for ``out``'s length.
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
    return out, {"invocations": wrote, "lanes": n_chunks * chunk, "chunks": n_chunks}
