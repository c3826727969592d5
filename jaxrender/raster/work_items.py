"""Work items of the coverage traversals: triangles by reference, chunks of (pixel, triangle)
items, the expansion of per-triangle item counts into items, and the exact window depth and
packed depth key every traversal shares, so that all of them give the same bits.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.raster.setup import SUBPIXEL, TriSetup
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

    def joined(self, more: "Triangles") -> "Triangles":
        """This list's slots followed by ``more``'s, in one list."""
        index = jnp.concatenate([self.index, more.index + self.verts.shape[0]])
        return Triangles(jnp.concatenate([self.verts, more.verts]), index,
                         jnp.concatenate([self.ok, more.ok]),
                         jnp.concatenate([self.tri, more.tri]))


@pytree_dataclass
class WorkChunk:
    """One chunk of work items; arrays of shape [capacity], but ``covered`` and ``depth``, which
    are [S, capacity] when each item tests S samples (``items_from_setup``)."""

    slot: Array  # int32 triangle slot in the setup arrays
    tri: Array  # int32 original triangle id
    px: Array  # int32 pixel column
    py: Array  # int32 pixel row
    covered: Array  # bool: live item whose sample point is inside the triangle
    depth: Array  # float32 window depth at the sample point (clamped to [0, 1])



def running_max(x: Array) -> Array:
    """Inclusive running maximum: lax.cummax on a GPU, where it is several times faster than
    an associative scan, and the associative scan on a CPU, where the reverse holds. The
    choice is made when the program is lowered for a platform."""
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
    an axis of 3: XLA CPU hands such a reduction to a library call, which cost a fifth of the
    frame."""
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


def chunk_items(setup: TriSetup, incl: Array, base: Array, capacity: int,
                offset: Array) -> WorkChunk:
    """The work items [base, base + capacity) of the box traversal (``incl``: the inclusive
    cumsum of ``setup.count``), from setup stored per triangle."""
    slot, j, live = owners(setup.count, incl, base, capacity)
    return items_from_setup(jax.tree_util.tree_map(lambda a: a[slot], setup), slot, j, live, offset)


def items_from_setup(su: TriSetup, slot: Array, j: Array, live: Array, offset: Array) -> WorkChunk:
    """Work items from the setup of each item's own triangle (arrays of shape [capacity]).
    ``offset`` int64[2]: one sample per item; int64[S, 2]: S samples per item, and the chunk's
    ``covered`` and ``depth`` are [S, capacity]. Each sample's edge values are the same exact
    integers either way, so each gives the bits it gives alone."""
    bw = su.bw
    row = jnp.floor((j.astype(jnp.float64) + 0.5) / bw.astype(jnp.float64)).astype(jnp.int32)
    px = su.x0 + (j - row * bw)
    py = su.y0 + row
    offs = offset.reshape(-1, 2, 1).astype(jnp.float64)  # [S, 2, 1] against [1, capacity]
    sx = (px * SUBPIXEL).astype(jnp.float64)[None] + offs[:, 0]
    sy = (py * SUBPIXEL).astype(jnp.float64)[None] + offs[:, 1]
    e = su.edge_a[None] * sx[..., None] + su.edge_b[None] * sy[..., None] + su.edge_c[None]
    # A reduce, not ands: it stores ``covered``, which the depth test and an alpha test both
    # read; fused into each of them instead, the edge functions were computed again in each.
    covered = live[None] & jnp.all(e + su.top_left[None] > 0, axis=-1)
    depth = window_depth([e[..., i] for i in range(3)], [su.z[None, :, i] for i in range(3)],
                         su.inv_area[None])
    if offset.ndim == 1:
        covered, depth = covered[0], depth[0]
    return WorkChunk(slot, su.tri, px, py, covered, depth)


def flat_samples(c: WorkChunk, width: int, height: int, live: Array | None = None):
    """A chunk's items as one entry per sample, sample-major: (covered, pixel, tri, depth),
    each [S * capacity] for a chunk of S samples ([capacity] for one), where sample s of pixel
    p is pixel s * width * height + p. ``live`` bool[S]: a dead sample's entries are never
    covered."""
    covered = c.covered if live is None else c.covered & live[:, None]
    pixel = c.py * width + c.px
    if c.covered.ndim == 1:
        return covered, pixel, c.tri, c.depth
    first = jnp.arange(c.covered.shape[0], dtype=pixel.dtype) * (width * height)
    pixel = pixel[None] + first[:, None]
    tri = jnp.broadcast_to(c.tri[None], c.covered.shape)
    return covered.reshape(-1), pixel.reshape(-1), tri.reshape(-1), c.depth.reshape(-1)


def depth_key(depth: Array, tri: Array) -> Array:
    """Pack (depth, id) into one int64 whose minimum is the nearest, lowest-id fragment.

    Non-negative float32 bit patterns order like the floats, so depth sorts first and ties go
    to the lower triangle index."""
    bits = jax.lax.bitcast_convert_type(depth, jnp.int32).astype(jnp.int64)
    return (bits << 32) | tri.astype(jnp.int64)
