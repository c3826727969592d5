"""Visibility buffer: packed ids, tile/wave classification, software VRS."""

import numpy as np
import pytest
from fdv_scenes import H, W, make_scene, rect_part

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines.visbuffer import IdLayout, decode, encode, pack_ids

VISBUFFER = get_pipeline("visbuffer")


def render(scene, **params):
    return VISBUFFER.render(scene, scene.camera, make_config("visbuffer", width=W, height=H,
                                                             **params))


def test_id_round_trip_and_overflow_refused():
    layout = IdLayout(batch_bits=16, primitive_bits=7, instance_bits=9)
    rng = np.random.default_rng(0)
    b = rng.integers(0, 2**16, 1000)
    p = rng.integers(0, 2**7, 1000)
    i = rng.integers(0, 2**9 - 1, 1000)
    ids = pack_ids(layout, b, p, i)
    assert ids.dtype == np.uint32
    for got, want in zip(layout.unpack(ids), (b, p, i)):
        np.testing.assert_array_equal(np.asarray(got), want)
    for bad in ((2**16, 0, 0), (0, 2**7, 0), (0, 0, 2**9)):
        with pytest.raises(OverflowError):
            pack_ids(layout, *(np.array([v]) for v in bad))
    with pytest.raises(OverflowError, match="empty"):  # all ones is the reserved empty id
        pack_ids(layout, np.array([2**16 - 1]), np.array([2**7 - 1]), np.array([2**9 - 1]))
    with pytest.raises(ValueError):
        IdLayout(16, 10, 9)  # 35 bits


def test_ids_in_the_frame_decode_to_the_triangles():
    scene = make_scene([rect_part(0, 0, 4, 4, 2.0), rect_part(2, 2, 6, 6, 4.0)])
    f = render(scene, id_layout="fixed")
    tri = np.asarray(decode(scene, f.aux["ids"], IdLayout()))
    assert set(np.unique(tri).tolist()) == {-1, 0, 1, 2, 3}
    assert int((tri >= 0).sum()) == 28
    assert int(f.counts["helper_lanes"]) == 0 and int(f.counts["shade_invocations"]) == 28


def test_an_id_field_overflow_is_counted():
    # Each rectangle is an object (instance): with 0 instance bits the second one overflows.
    # (render() raises OverflowError on any counted overflow; see program.check_overflow.)
    scene = make_scene([rect_part(0, 0, 4, 4, 2.0), rect_part(2, 2, 6, 6, 4.0)])
    tri = np.array([[0, 1, 2, 3, -1]], np.int32)
    _, over = encode(scene, tri, IdLayout(16, 7, 0))
    assert int(over) == 2  # triangles 2 and 3 belong to instance 1
    ids, over = encode(scene, tri, IdLayout())
    assert int(over) == 0
    np.testing.assert_array_equal(np.asarray(decode(scene, ids, IdLayout())), tri)


@pytest.mark.parametrize("tiling", ["loose", "tiles"])
def test_vrs_off_plans_as_the_general_path_at_full_rate(tiling):
    # vrs = "off" skips the coarse-pixel sort (each covered pixel is its own anchor); a fixed
    # 1x1 rate runs that sort, and must plan the same shading.
    scene = make_scene([rect_part(0, 0, 10, 7, 2.0, tilt=0.3), rect_part(3, 2, W, H, 4.0)])
    off = render(scene, tiling=tiling)
    general = render(scene, tiling=tiling, vrs="fixed", vrs_rate="1x1")
    np.testing.assert_array_equal(np.asarray(off.image), np.asarray(general.image),
                                  err_msg=f"{tiling}: image")
    for key in ("shade_invocations", "waves", "unfilled_lanes", "vertex_invocations"):
        assert int(off.counts[key]) == int(general.counts[key]), f"{tiling}: {key}"
    np.testing.assert_array_equal(np.asarray(off.aux["shade_count"]),
                                  np.asarray(general.aux["shade_count"]), err_msg=tiling)


def test_vrs_2x2_shades_a_quarter_and_broadcasts():
    scene = make_scene([rect_part(0, 0, W, H, 3.0, tilt=0.5)])
    full = render(scene, tiling="tiles")
    f = render(scene, vrs="fixed", vrs_rate="2x2", tiling="tiles")
    assert int(full.counts["shade_invocations"]) == W * H
    assert int(f.counts["shade_invocations"]) == W * H // 4
    img = np.asarray(f.image)
    top_left = img[::2, ::2]
    np.testing.assert_array_equal(img, np.repeat(np.repeat(top_left, 2, 0), 2, 1))
    np.testing.assert_allclose(top_left, np.asarray(full.image)[::2, ::2], atol=1e-6)
    # Waves: the 16 x 12 coarse grid is 2 x 2 coarse tiles of up to 8 x 8; in waves of 32
    # (4 coarse rows): tiles of 8, 8, 4 and 4 rows -> 2 + 2 + 1 + 1 = 6 waves for 192 lanes.
    assert int(f.counts["waves"]) == 6
    np.testing.assert_allclose(float(f.counts["lane_utilization"]), 192 / (6 * 32))
    # Full rate: 4 x 3 tiles of 8x8, two waves each.
    assert int(full.counts["waves"]) == 24
    np.testing.assert_allclose(float(full.counts["lane_utilization"]), 1.0)
