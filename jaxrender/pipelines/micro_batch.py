"""Micro batches and Decima's 32-bit visibility id (GDC 2022).

Geometry is drawn in batches: a run of consecutive objects with the same material and the same
triangle count is one instanced batch (the leaf cards of the foliage are instances of one card;
each object's triangles are its instance's). A batch is split into micro batches of at most
2^16 triangles and as many instances as the id leaves room for. The id packs, most significant
first, the micro batch (16 bits), the primitive inside the micro batch (ceil(log2(primitives))
bits, the batch's primitive count capped at 2^16) and the instance inside the micro batch (the
rest of the low 16 bits). When a batch has more instances than its instance bits hold, the next
ones go into the next micro batch, as the talk does, instead of failing. With software VRS the
shading rate travels in the id's top 2 bits (the micro batch field keeps 14).

A per-micro-batch table (first triangle, primitives per instance, primitive bits) decodes an
id back to its triangle: ``triangle = first + instance * primitives + primitive``. The table
is built in the program from the scene's traced arrays, sized by the triangle count (a micro
batch holds at least one triangle); a micro batch index past its field's range is an overflow,
counted and reported, never dropped.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from jaxrender.pipelines.quads import BIG, first_of_segment_index
from jaxrender.types import Array

EMPTY_ID = 0xFFFFFFFF
LOW_BITS = 16  # primitive + instance
MAX_PRIMITIVES = 1 << LOW_BITS  # per micro batch
RATE_BITS = 2  # the VRS rate, 0..3, in the top bits when VRS is on


class MicroBatches(NamedTuple):
    """Per triangle: ``batch`` (its micro batch), ``prim`` and ``inst`` (inside the micro
    batch), ``prim_bits``; per micro batch (int32[T], the first ``count`` used): ``first``
    triangle, ``prims`` (primitives per instance) and ``table_bits`` (primitive bits)."""

    batch: Array
    prim: Array
    inst: Array
    prim_bits: Array
    first: Array
    prims: Array
    table_bits: Array
    count: Array


def _objects(tri_object: Array, tri_material: Array):
    """Per object (int32[T] slots, objects numbered in order): its first triangle, its
    triangle count, whether it exists, and whether it starts a new batch (its material or
    triangle count differs from the object before it)."""
    n = tri_object.shape[0]
    idx = jnp.arange(n, dtype=jnp.int32)
    obj_first = jnp.full((n,), BIG, jnp.int32).at[tri_object].min(idx, mode="drop")
    obj_count = jnp.zeros((n,), jnp.int32).at[tri_object].add(1, mode="drop")
    exists = obj_count > 0
    obj_mat = tri_material[jnp.minimum(obj_first, n - 1)]
    prev = lambda a, fill: jnp.concatenate([jnp.full((1,), fill, a.dtype), a[:-1]])  # noqa
    new_batch = exists & ((idx == 0) | ~prev(exists, False) | (obj_count != prev(obj_count, -1))
                          | (obj_mat != prev(obj_mat, -1)))
    return obj_first, obj_count, exists, new_batch


def triangle_batches(tri_object: Array, tri_material: Array) -> Array:
    """int32[T]: the batch (the instanced draw) of each triangle, numbered in draw order."""
    _, _, _, new_batch = _objects(tri_object, tri_material)
    return (jnp.cumsum(new_batch, dtype=jnp.int32) - 1)[tri_object]


def micro_batches(tri_object: Array, tri_material: Array) -> MicroBatches:
    """The micro batches of triangles whose objects (int32[T], contiguous, numbered in order)
    and materials are given."""
    n = tri_object.shape[0]
    idx = jnp.arange(n, dtype=jnp.int32)
    obj_first, obj_count, exists, new_batch = _objects(tri_object, tri_material)
    inst = idx - first_of_segment_index(new_batch | ~exists)  # instance inside its batch
    per_instance = jnp.minimum(obj_count, MAX_PRIMITIVES)
    pbits = jnp.where(exists, bits_for(per_instance), 0)
    ibits = LOW_BITS - pbits
    inst_local = inst & ((1 << ibits) - 1)
    chunks = (obj_count + MAX_PRIMITIVES - 1) // MAX_PRIMITIVES
    opens = exists & (inst_local == 0)  # the first instance of a micro batch's instances
    base = jnp.cumsum(jnp.where(opens, chunks, 0), dtype=jnp.int32) - jnp.where(opens, chunks, 0)
    opener = idx - inst_local
    # Per triangle.
    o = tri_object
    local = idx - obj_first[o]
    batch = base[opener[o]] + local // MAX_PRIMITIVES
    prim = local % MAX_PRIMITIVES
    starts = (prim == 0) & (inst_local[o] == 0)
    slot = jnp.where(starts, batch, n)
    first = jnp.zeros((n,), jnp.int32).at[slot].set(idx, mode="drop")
    prims = jnp.zeros((n,), jnp.int32).at[slot].set(obj_count[o], mode="drop")
    table_bits = jnp.zeros((n,), jnp.int32).at[slot].set(pbits[o], mode="drop")
    count = jnp.sum(jnp.where(opens, chunks, 0), dtype=jnp.int32)
    return MicroBatches(batch, prim, inst_local[o], pbits[o], first, prims, table_bits, count)


def bits_for(n: Array) -> Array:
    """int32 ceil(log2(n)) for n >= 1 (0 for n = 1): exact, by counting powers of two."""
    n = jnp.asarray(n, jnp.int32)
    return sum(((n - 1) >> k > 0).astype(jnp.int32) for k in range(31))


def batch_bits(rate_bits: int) -> int:
    return 32 - LOW_BITS - int(rate_bits)


def pack(mb: MicroBatches, tri: Array, rate: Array | None, rate_bits: int):
    """int32 triangles (-1 empty) and rate codes -> (uint32 ids, overflow count): a micro
    batch past its field, or an id equal to the empty id, overflows."""
    t = jnp.maximum(tri, 0)
    batch, prim, inst, pbits = mb.batch[t], mb.prim[t], mb.inst[t], mb.prim_bits[t]
    u = lambda a: jnp.asarray(a).astype(jnp.uint32)  # noqa: E731
    ibits = LOW_BITS - pbits
    ids = (u(batch) << LOW_BITS) | (u(prim) << u(ibits)) | u(inst)
    over = batch >= (1 << batch_bits(rate_bits))
    if rate_bits:
        ids = ids | (u(rate) << (32 - rate_bits))
    over = over | (ids == jnp.uint32(EMPTY_ID))
    covered = tri >= 0
    return (jnp.where(covered, ids, jnp.uint32(EMPTY_ID)),
            jnp.sum(over & covered, dtype=jnp.int32))


def unpack(mb: MicroBatches, ids: Array, rate_bits: int) -> tuple[Array, Array]:
    """uint32 ids -> (int32 triangles, -1 for the empty id; int32 rate codes, 0 without
    rate bits)."""
    ids = jnp.asarray(ids, jnp.uint32)
    batch = ((ids >> LOW_BITS) & jnp.uint32((1 << batch_bits(rate_bits)) - 1)).astype(jnp.int32)
    batch = jnp.minimum(batch, mb.first.shape[0] - 1)
    low = (ids & jnp.uint32(MAX_PRIMITIVES - 1)).astype(jnp.int32)
    ibits = LOW_BITS - mb.table_bits[batch]
    prim = low >> ibits
    inst = low & ((1 << ibits) - 1)
    tri = mb.first[batch] + inst * mb.prims[batch] + prim
    empty = ids == jnp.uint32(EMPTY_ID)
    rate = ((ids >> (32 - rate_bits)).astype(jnp.int32) if rate_bits
            else jnp.zeros(ids.shape, jnp.int32))
    return jnp.where(empty, -1, tri), jnp.where(empty, 0, rate)
