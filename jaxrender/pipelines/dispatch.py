"""Work lists and chunked dispatch: the one place where shading work is launched.

A pipeline that shades fewer points must run fewer shader evaluations, or its time would not
follow its work and a comparison of architectures would measure the simulation. The points to
shade are compacted into a ``WorkList`` (``compaction.compact_indices``), and ``shade()`` runs
over it in whole chunks of a static size, like DispatchIndirect: the compiled program evaluates
the shader over the chunks that hold work (``launch_mode``: in a loop, or in one launch of a
power-of-two number of chunks), never over the full screen with a mask. The counts are read
off that same work list, so they cannot disagree with the work done (``count`` items,
``chunks * chunk`` lanes launched). One pass shades elsewhere: the transparent pass's test,
shading and composite share one launch over the fragment list's filled prefix, its lanes
behind the opaque depth idle (``transparency.blend_on_prefix``).
"""

from __future__ import annotations

import dataclasses
import os
from typing import Callable

import jax
import jax.numpy as jnp

from jaxrender.compaction import compact_indices
from jaxrender.fusion import whole_rows
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
    launched: Array | None = None  # chunks launched, when a launch rounded the count up
    launched_lanes: Array | None = None  # lanes launched, when the launches differ in size

    @classmethod
    def of(cls, active: Array) -> "WorkList":
        """The True entries of bool[N] in order (padded with 0) and their count."""
        items, count = compact_indices(active, active.shape[0])
        return cls(items, count)

    @property
    def chunks(self) -> Array:
        """Chunks launched: the count's, or more where a launch rounded it up."""
        if self.launched is not None:
            return self.launched
        return (self.count + self.chunk - 1) // self.chunk

    @property
    def lanes(self) -> Array:
        """Lanes launched: whole chunks, the last one's idle lanes included."""
        if self.launched_lanes is not None:
            return self.launched_lanes
        return self.chunks * self.chunk

    @property
    def idle_lanes(self) -> Array:
        return self.lanes - self.invocations

    @property
    def counts(self) -> dict:
        return {"invocations": self.invocations, "lanes": self.lanes, "chunks": self.chunks}


LAUNCH_MODES = ("loop", "blocks", "switch", "binary")
ENV_LAUNCH = "JAXRENDER_DISPATCH"
BLOCK = 4  # chunks in one launch of the blocks mode
# The default: about a quarter of the loop's host reads for the same lanes, and two compiled
# launch sizes against the switch's five or six (timings: RESULTS.md, seventeenth session).
DEFAULT_LAUNCH = "blocks"


def launch_mode(default: str = DEFAULT_LAUNCH) -> str:
    """How a work list's chunks are launched, read when a program is traced:
    ``JAXRENDER_DISPATCH`` (loop, blocks, switch or binary), else ``default`` (the list's own:
    ``DEFAULT_LAUNCH`` for all but DACS's levels, which take the switch).

    On a GPU every loop iteration and every branch reads a value back to the host before it
    launches (``bench.round_trips`` counts them), so the modes trade those reads against idle
    lanes and against copies of the shader compiled (one per launch size):

    - loop: one ``while`` iteration per chunk: n + 1 reads for n chunks, one size.
    - blocks: a loop over blocks of BLOCK chunks, then a loop over the chunks left: n // 4 +
      n % 4 + 2 reads, exactly the loop's lanes, two sizes.
    - switch: one launch of the smallest power-of-two number of chunks that holds the list:
      one read; up to half the lanes idle (counted in ``lanes``); a size per power of two.
    - binary: one launch per set bit of the chunk count: a read per bit, exactly the loop's
      lanes, a size per bit."""
    return named_launch_mode() or default


def named_launch_mode() -> str:
    """The launch mode ``JAXRENDER_DISPATCH`` names ("" when unset): it also sends deferred's
    screen passes (``shade_screen``) and the transparent pass (``transparency.transparent_pass``)
    back to the chunked dispatch, so a program depends on whether a mode is named, not only on
    the mode in force."""
    said = os.environ.get(ENV_LAUNCH, "").strip().lower()
    if said and said not in LAUNCH_MODES:
        raise ValueError(f"{ENV_LAUNCH}={said!r}: expected one of {', '.join(LAUNCH_MODES)}")
    return said


def launches_once(chunk: int) -> bool:
    """Whether a pass that can launch its whole list at once does: with the auto chunk and no
    ``JAXRENDER_DISPATCH`` mode named (a chunk given, or a mode named, asks for chunks)."""
    return int(chunk) == 0 and not named_launch_mode()


def _launch(n_chunks: Array, max_chunks: int, chunk: int, launch, acc, mode: str):
    """Run ``launch(start, size, acc) -> acc`` over lanes ``0 .. n_chunks * chunk - 1`` (start
    traced, size static) as ``mode`` says; returns (acc, chunks launched)."""
    if mode == "loop":
        acc = jax.lax.fori_loop(0, n_chunks, lambda k, a: launch(k * chunk, chunk, a), acc)
        return acc, n_chunks
    if mode == "blocks":
        n_blocks = jnp.zeros_like(n_chunks)
        if max_chunks >= BLOCK:  # a list that never fills a block launches none
            big, n_blocks = chunk * BLOCK, n_chunks // BLOCK
            acc = jax.lax.fori_loop(0, n_blocks, lambda k, a: launch(k * big, big, a), acc)
        acc = jax.lax.fori_loop(n_blocks * BLOCK, n_chunks,
                                lambda k, a: launch(k * chunk, chunk, a), acc)
        return acc, n_chunks
    bits = max(int(max_chunks) - 1, 0).bit_length()  # 2**bits >= max_chunks
    if mode == "binary":
        for b in reversed(range(bits + 1)):
            start = (n_chunks >> (b + 1) << (b + 1)) * chunk
            acc = jax.lax.cond(((n_chunks >> b) & 1) == 1,
                               lambda a, s=start, b=b: launch(s, chunk << b, a),
                               lambda a: a, acc)
        return acc, n_chunks
    if mode != "switch":
        raise ValueError(f"unknown launch mode {mode!r}: expected one of {LAUNCH_MODES}")
    ceil_log2 = jnp.where(n_chunks <= 1, 0, 32 - jax.lax.clz(jnp.maximum(n_chunks - 1, 1)))
    branch = jnp.where(n_chunks == 0, 0, 1 + ceil_log2)
    zero = jnp.zeros((), jnp.int32)
    branches = [lambda a: a] + [lambda a, b=b: launch(zero, chunk << b, a)
                                for b in range(bits + 1)]
    acc = jax.lax.switch(jnp.minimum(branch, bits + 1), branches, acc)
    return acc, jnp.where(n_chunks == 0, 0, jnp.int32(1) << ceil_log2)


def _chunks_of(count: Array, chunk: int) -> Array:
    return (count + chunk - 1) // chunk


def _rows(out) -> int:
    """The entries of ``out``: an array, or a tuple of arrays of one length (a G-buffer's
    fields, each stored as its own array)."""
    return jax.tree.leaves(out)[0].shape[0]


def _scatter(acc, index: Array, vals, **kw):
    """``acc[index] = vals`` leaf by leaf (out-of-range indices dropped)."""
    return jax.tree.map(lambda a, v: a.at[index].set(v.astype(a.dtype), mode="drop", **kw),
                        acc, vals)


def run(work: WorkList, fn: Callable[[Array, Array], Array], out: Array,
        chunk: int, default_mode: str = DEFAULT_LAUNCH) -> tuple[Array, WorkList]:
    """For the live items of ``work``, write ``fn(items int32[L], live bool[L]) ->
    values[L, ...]`` into ``out[items]``, ``L`` lanes a launch (a multiple of ``chunk``).
    ``out`` and the values may be matching tuples of arrays.

    Launches whole chunks covering the count (``launch_mode(default_mode)``); padding lanes
    are passed live=False and their results are discarded. ``chunk`` 0 picks ``auto_chunk``
    for the list. Returns (out, the work list with its dispatch counts).
    """
    items, n = work.items, work.count
    chunk = int(min(resolve_chunk(chunk, items.shape[0]), max(items.shape[0], 1)))
    mode = launch_mode(default_mode)
    max_chunks = max(-(-items.shape[0] // chunk), 1)
    # Zeros past the list for the lanes of the largest launch past it (a block ends at or
    # before the last chunk's end).
    span = chunk if mode in ("loop", "blocks") else chunk << max(max_chunks - 1, 0).bit_length()
    padded = jnp.concatenate([items, jnp.zeros((span,), items.dtype)])
    sentinel = _rows(out)  # out-of-range index: scatter drops the lane

    def launch(start, size, acc):
        lane_items = jax.lax.dynamic_slice(padded, (start,), (size,))
        live = start + jnp.arange(size, dtype=jnp.int32) < n
        vals = whole_rows(fn(lane_items, live))  # not once per channel inside the scatter
        return _scatter(acc, jnp.where(live, lane_items, sentinel), vals)

    out, launched = _launch(_chunks_of(n, chunk), max_chunks, chunk, launch, out, mode)
    return out, WorkList(items, n, n, chunk, launched)


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
    max_lanes: int | None = None,
) -> tuple[Array, WorkList]:
    """Launch lanes ``0 .. n-1`` in chunks: ``fn(lanes int32[chunk], live bool[chunk])`` returns
    ``(dest int32[chunk], values[chunk, ...], write bool[chunk])`` and ``out[dest] = values``
    where ``live & write``. For work whose lanes are not one-to-one with outputs (2x2 quads with
    helper lanes, waves with idle lanes): every lane is evaluated, only some write.

    Returns (out, the lane list as a WorkList: ``count`` n lanes, ``invocations`` the lanes
    that wrote). ``chunk`` 0 picks ``auto_chunk`` for ``out``'s length. ``max_lanes``: the
    most ``n`` can be (static; default ``out``'s length), which sizes the largest launch.
    """
    chunk = resolve_chunk(chunk, out.shape[0])
    sentinel = out.shape[0]

    def launch(start, size, carry):
        acc, wrote = carry
        lanes = start + jnp.arange(size, dtype=jnp.int32)
        live = lanes < n
        dest, vals, write = fn(lanes, live)
        vals = whole_rows(vals)
        ok = live & write
        acc = acc.at[jnp.where(ok, dest, sentinel)].set(vals, mode="drop")
        return acc, wrote + jnp.sum(ok, dtype=jnp.int32)

    max_chunks = max(-(-int(max_lanes or out.shape[0]) // chunk), 1)
    (out, wrote), launched = _launch(_chunks_of(n, chunk), max_chunks, chunk, launch,
                                     (out, jnp.int32(0)), launch_mode())
    return out, WorkList(jnp.zeros((0,), jnp.int32), n, wrote, chunk, launched)


DENSE_TIERS = (2,)  # the reference's passes: compacted into half the lanes, or in place


def shade_dense(
    active: Array,
    points_of: Callable[[Array], object],
    shade_fn: Callable[[object], Array],
    out: Array,
    tiers: tuple[int, ...] = DENSE_TIERS,
) -> tuple[Array, WorkList]:
    """``shade`` of the True entries of bool[N] ``active`` in one launch (one host read), for
    lists that often fill most of their launch (the reference's samples, 64 screens a frame): the
    active entries compacted into the smallest launch of N // d lanes (d in ``tiers``) that
    holds them, and scattered back; past N // min(tiers), every entry runs in place, inactive
    lanes idle, which spares the compaction and the scatter where they would cost more than the
    idle lanes (on an H200 the reference's room, 90% covered, is 3% slower compacted into half,
    foliage, 37% covered, 17% faster). Each tier is one more copy of the shader compiled.
    Nothing is launched for an empty list. Counts: ``count`` and ``invocations`` the active
    entries, one launch, its lanes in ``lanes``."""
    if any(int(d) < 2 for d in tiers):
        raise ValueError(f"shade_dense: every tier d launches N // d lanes and must be at least "
                         f"2 (N lanes run in place past the largest tier), got tiers={tiers!r}")
    n = active.shape[0]
    sizes = sorted({n // d for d in tiers if n // d > 0})
    count = jnp.sum(active, dtype=jnp.int32)

    def keep(a, v):
        return jnp.where(active.reshape(active.shape + (1,) * (v.ndim - 1)), v.astype(a.dtype), a)

    def in_place(acc):
        pts = points_of(jnp.arange(n, dtype=jnp.int32))
        pts = dataclasses.replace(pts, valid=pts.valid & active)
        return jax.tree.map(keep, acc, shade_fn(pts))

    def compacted(size: int):
        def launch(acc):
            items, _ = compact_indices(active, size)
            live = jnp.arange(size, dtype=jnp.int32) < count
            pts = points_of(items)
            pts = dataclasses.replace(pts, valid=pts.valid & live)
            return _scatter(acc, jnp.where(live, items, n), whole_rows(shade_fn(pts)),
                            unique_indices=True)
        return launch

    # 0: nothing; 1 + i: the i-th size; 1 + len(sizes): in place.
    which = jnp.where(count == 0, 0, 1 + sum((count > m).astype(jnp.int32) for m in sizes))
    out = jax.lax.switch(which, [lambda acc: acc] + [compacted(m) for m in sizes] + [in_place],
                         out)
    lanes = jnp.asarray([0] + sizes + [n], jnp.int32)[which]
    items = jnp.zeros((0,), jnp.int32)
    return out, WorkList(items, count, count, n, (count > 0).astype(jnp.int32), lanes)


# Deferred's screen passes cover from about a third (foliage) to nine tenths (room) of the
# built-in scenes' screens: three compacted sizes keep the idle lanes under half of those
# launched above an eighth of the screen, with one host read a pass, not one a chunk
# (timings: RESULTS.md, nineteenth session).
SCREEN_TIERS = (8, 4, 2)


def shade_screen(
    active: Array,
    points_of: Callable[[Array], object],
    shade_fn: Callable[[object], Array],
    out: Array,
    chunk: int = DEFAULT_CHUNK,
) -> tuple[Array, WorkList]:
    """``shade`` of the True entries of a screen-sized bool[N] ``active`` (one entry per pixel
    or sample). With the auto chunk and no ``JAXRENDER_DISPATCH`` set: one ``shade_dense``
    launch over ``SCREEN_TIERS`` (one host read). With a chunk given, or a launch mode named in
    ``JAXRENDER_DISPATCH``: the chunked ``shade`` of its work list in that mode."""
    if launches_once(chunk):
        return shade_dense(active, points_of, shade_fn, out, SCREEN_TIERS)
    return shade(WorkList.of(active), points_of, shade_fn, out, chunk)
