"""Decima's 32-bit ids: micro batches of <= 2^16 triangles, primitive bits sized per batch,
instances in the rest, the wrap into the next micro batch, the VRS rate in the top bits."""

import jax.numpy as jnp
import numpy as np
import pytest
from fdv_scenes import H, W, make_scene, rect_part

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines.micro_batch import (EMPTY_ID, bits_for, micro_batches, pack,
                                             triangle_batches, unpack)

CARD = 3  # triangles per instance of batch A: 2 primitive bits, 14 instance bits
PER_MICRO = 1 << 14  # instances of A per micro batch
A_INSTANCES = PER_MICRO + 2  # one more than fits: the last two wrap into a second micro batch
BIG_PRIMS = (1 << 16) + 1  # batch C: one instance too many primitives for one micro batch


def _layout():
    """Objects (triangle -> object, material): A = A_INSTANCES instances of a 3-triangle mesh;
    B = one 5-triangle object (material 1); C = one object of 2^16 + 1 triangles; D = three
    1-triangle objects (0 primitive bits, 16 instance bits)."""
    objs, mats = [np.repeat(np.arange(A_INSTANCES), CARD)], [np.zeros(A_INSTANCES * CARD)]
    o = A_INSTANCES
    for n, m in ((5, 1), (BIG_PRIMS, 1), (1, 2), (1, 2), (1, 2)):
        objs.append(np.full(n, o))
        mats.append(np.full(n, m))
        o += 1
    return (jnp.asarray(np.concatenate(objs), jnp.int32),
            jnp.asarray(np.concatenate(mats), jnp.int32))


@pytest.fixture(scope="module")
def layout():
    tri_object, tri_material = _layout()
    return micro_batches(tri_object, tri_material), tri_object.shape[0]


def test_bits_for_is_ceil_log2():
    n = np.array([1, 2, 3, 4, 5, 255, 256, 257, 65535, 65536, 65537])
    want = np.ceil(np.log2(n)).astype(int)
    np.testing.assert_array_equal(np.asarray(bits_for(jnp.asarray(n, jnp.int32))), want)


def test_fields_at_their_boundaries(layout):
    mb, n = layout
    batch, prim, inst, pbits = (np.asarray(a) for a in (mb.batch, mb.prim, mb.inst,
                                                         mb.prim_bits))
    a_end = A_INSTANCES * CARD
    # A: 2 primitive bits; instance 2^14 - 1 is the last of micro batch 0 ...
    last = (PER_MICRO - 1) * CARD + 2
    assert (batch[last], prim[last], inst[last], pbits[last]) == (0, 2, PER_MICRO - 1, 2)
    # ... and instance 2^14 wraps: micro batch 1, instance 0.
    wrap = PER_MICRO * CARD
    assert (batch[wrap], prim[wrap], inst[wrap]) == (1, 0, 0)
    assert (batch[a_end - 1], inst[a_end - 1]) == (1, 1)
    # B: its own micro batch, 3 primitive bits.
    assert (batch[a_end], batch[a_end + 4], prim[a_end + 4], pbits[a_end]) == (2, 2, 4, 3)
    # C: 2^16 primitives fill micro batch 3 (16 bits, no instance bits), the last one is 4.
    c0 = a_end + 5
    assert (batch[c0 + (1 << 16) - 1], prim[c0 + (1 << 16) - 1], pbits[c0]) == (3, 65535, 16)
    assert (batch[c0 + (1 << 16)], prim[c0 + (1 << 16)]) == (4, 0)
    # D: three 1-triangle instances, 0 primitive bits, in one micro batch.
    np.testing.assert_array_equal(batch[-3:], [5, 5, 5])
    np.testing.assert_array_equal(inst[-3:], [0, 1, 2])
    assert int(mb.count) == 6 and int(pbits[-1]) == 0


def test_batches_are_runs_of_instances_of_one_mesh_and_material():
    tri_object, tri_material = _layout()
    got = np.asarray(triangle_batches(tri_object, tri_material))
    a_end = A_INSTANCES * CARD
    want = np.concatenate([np.zeros(a_end), np.full(5, 1), np.full(BIG_PRIMS, 2),
                           np.full(3, 3)])
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("rate_bits", [0, 2])
def test_pack_unpack_round_trip(layout, rate_bits):
    mb, n = layout
    tri = jnp.concatenate([jnp.arange(n, dtype=jnp.int32), jnp.asarray([-1], jnp.int32)])
    rate = (tri * 7) % 4
    ids, over = pack(mb, tri, rate, rate_bits)
    assert int(over) == 0
    got_tri, got_rate = unpack(mb, ids, rate_bits)
    np.testing.assert_array_equal(np.asarray(got_tri), np.asarray(tri), err_msg="triangles")
    want_rate = np.where(np.asarray(tri) >= 0, np.asarray(rate), 0) if rate_bits else 0
    np.testing.assert_array_equal(np.asarray(got_rate), want_rate + 0 * np.asarray(tri))
    ids = np.asarray(ids)
    assert ids[-1] == EMPTY_ID
    # The layout, bit by bit: micro batch above bit 16, then primitive, then instance.
    last = (PER_MICRO - 1) * CARD + 2
    want = (0 << 16) | (2 << 14) | (PER_MICRO - 1)
    if rate_bits:
        want |= int(rate[last]) << 30
    assert int(ids[last]) == want
    wrap = PER_MICRO * CARD + 1
    want = (1 << 16) | (1 << 14) | 0
    if rate_bits:
        want |= int(rate[wrap]) << 30
    assert int(ids[wrap]) == want


def test_a_micro_batch_past_its_field_is_an_overflow():
    # 2^14 + 1 single-triangle objects of alternating materials: each its own batch and micro
    # batch; with the rate in the top bits only 2^14 micro batches fit.
    n = (1 << 14) + 1
    tri_object = jnp.arange(n, dtype=jnp.int32)
    mb = micro_batches(tri_object, tri_object % 2)
    assert int(mb.count) == n
    tri = jnp.arange(n, dtype=jnp.int32)
    assert int(pack(mb, tri, jnp.zeros(n, jnp.int32), 2)[1]) == 1
    assert int(pack(mb, tri, None, 0)[1]) == 0


def test_frame_ids_decode_to_the_visible_triangles_with_vrs_in_the_top_bits():
    scene = make_scene([rect_part(0, 0, 8, 8, 2.0), rect_part(4, 4, 16, 12, 4.0)])
    vb = get_pipeline("visbuffer")
    plain = vb.render(scene, scene.camera, make_config("visbuffer", width=W, height=H))
    fixed = vb.render(scene, scene.camera, make_config("visbuffer", width=W, height=H,
                                                       id_layout="fixed"))
    vrs = vb.render(scene, scene.camera, make_config("visbuffer", width=W, height=H,
                                                     vrs="fixed", vrs_rate="2x2",
                                                     tiling="tiles"))  # test_visbuffer's
    mb = micro_batches(scene.tri_object, scene.tri_material)
    tri, _ = unpack(mb, plain.aux["ids"], 0)
    tri_v, rate_v = unpack(mb, vrs.aux["ids"], 2)
    np.testing.assert_array_equal(np.asarray(tri_v), np.asarray(tri))
    covered = np.asarray(tri) >= 0
    assert covered.sum() == 8 * 8 + 12 * 8 - 4 * 4
    np.testing.assert_array_equal(np.asarray(rate_v)[covered], 3)  # 2x2 travels in the id
    np.testing.assert_array_equal(np.asarray(plain.image), np.asarray(fixed.image))
    assert not np.array_equal(np.asarray(plain.aux["ids"]), np.asarray(fixed.aux["ids"]))
