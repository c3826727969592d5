"""The fixed 32-bit visibility id layout (``id_layout = "fixed"``): batch, primitive and
instance fields of static widths, the instance being the object and the batch a run of
2^primitive_bits of its triangles. An id that does not fit is an overflow, counted and
reported (``pack_ids`` raises). Decima's own layout, sized per batch, is ``micro_batch``.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.micro_batch import EMPTY_ID
from jaxrender.pipelines.quads import BIG


@dataclass(frozen=True)
class IdLayout:
    """Bit fields of the 32-bit visibility id, most significant first: micro batch, primitive
    (inside its batch), instance. A triangle ``t`` of object (instance) ``i`` whose first
    triangle is ``f`` has local index ``t - f = batch * 2^primitive_bits + primitive``."""

    batch_bits: int = 16
    primitive_bits: int = 7
    instance_bits: int = 9

    def __post_init__(self):
        bits = (self.batch_bits, self.primitive_bits, self.instance_bits)
        if min(bits) < 0 or sum(bits) > 32:
            raise ValueError(f"id layout {bits}: fields must be >= 0 and sum to <= 32 bits")

    def pack(self, batch, prim, inst):
        """(uint32 ids, bool overflow) for int32 arrays; an overflowing field, or an id equal to
        the empty value 0xFFFFFFFF, sets overflow."""
        batch, prim, inst = (jnp.asarray(a, jnp.int32) for a in (batch, prim, inst))
        over = jnp.zeros(batch.shape, bool)
        for v, bits in ((batch, self.batch_bits), (prim, self.primitive_bits),
                        (inst, self.instance_bits)):
            over = over | (v < 0)
            if bits < 31:  # an int32 cannot exceed a wider field
                over = over | (v >= (1 << bits))
        u = lambda a: a.astype(jnp.uint32)  # noqa: E731
        pb, ib = self.primitive_bits, self.instance_bits
        ids = (u(batch) << (pb + ib)) | (u(prim) << ib) | u(inst)
        if self.batch_bits + pb + ib == 32:  # else the all-ones id is unreachable
            over = over | (ids == jnp.uint32(EMPTY_ID))
        return ids, over

    def unpack(self, ids):
        """uint32 ids -> (batch, primitive, instance) int32."""
        ids = jnp.asarray(ids, jnp.uint32)
        pb, ib = self.primitive_bits, self.instance_bits
        mask = lambda b: jnp.uint32((1 << b) - 1)  # noqa: E731
        inst = ids & mask(ib)
        prim = (ids >> ib) & mask(pb)
        batch = (ids >> (pb + ib)) & mask(self.batch_bits)
        return batch.astype(jnp.int32), prim.astype(jnp.int32), inst.astype(jnp.int32)


def pack_ids(layout: IdLayout, batch, prim, inst):
    """Eager packing that refuses overflow: raises OverflowError naming the field."""
    b, p, i = (np.asarray(a) for a in (batch, prim, inst))
    for name, v, bits in (("batch", b, layout.batch_bits), ("primitive", p, layout.primitive_bits),
                          ("instance", i, layout.instance_bits)):
        if v.size and (v.min() < 0 or v.max() >= (1 << bits)):
            raise OverflowError(f"visibility id: {name} value {int(v.max())} does not fit in "
                                f"{bits} bits")
    ids, over = layout.pack(b, p, i)
    if bool(jnp.any(over)):
        raise OverflowError("visibility id: the packed id equals the reserved empty id")
    return ids


def object_first_triangle(scene) -> jax.Array:
    """int32[T]: entry i is the first triangle of object i (objects are contiguous)."""
    t = scene.faces.shape[0]
    return jnp.full((t,), BIG, jnp.int32).at[scene.tri_object].min(
        jnp.arange(t, dtype=jnp.int32), mode="drop")


def encode(scene, tri, layout: IdLayout):
    """int32 triangle ids (-1 = empty) -> (uint32 packed ids, overflow count)."""
    first = object_first_triangle(scene)
    t = jnp.maximum(tri, 0)
    inst = scene.tri_object[t]
    local = t - first[inst]
    ids, over = layout.pack(local >> layout.primitive_bits,
                            local & ((1 << layout.primitive_bits) - 1), inst)
    covered = tri >= 0
    return (jnp.where(covered, ids, jnp.uint32(EMPTY_ID)),
            jnp.sum(over & covered, dtype=jnp.int32))


def decode(scene, ids, layout: IdLayout):
    """uint32 packed ids -> int32 triangle ids (-1 for the empty id)."""
    batch, prim, inst = layout.unpack(ids)
    first = object_first_triangle(scene)
    tri = first[jnp.minimum(inst, first.shape[0] - 1)] + (batch << layout.primitive_bits) + prim
    return jnp.where(ids == jnp.uint32(EMPTY_ID), -1, tri)
