"""Forward shading: hand-worked invocation and helper-lane counts, pre-pass, foliage overdraw."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from fdv_scenes import FOLIAGE_CARDS, H, W, foliage_scene, make_scene, rect_part, tri_part

from jaxrender.pipelines import COUNT_KEYS, get_pipeline, make_config, program
from jaxrender.sorting import EMPTY
from tests.jaxpr_walk import all_equations

FORWARD = get_pipeline("forward")
NEAR = rect_part(0, 0, 4, 4, 2.0)  # 16 pixels
FAR = rect_part(2, 2, 6, 6, 4.0)  # 16 pixels, 4 of them behind NEAR


def counts(scene, **params):
    frame = FORWARD.render(scene, scene.camera, make_config("forward", width=W, height=H,
                                                            **params))
    return {k: float(v) for k, v in frame.counts.items()}, frame


@pytest.mark.parametrize("order, prepass, expected", [
    ("front_to_back", False, 28),  # NEAR 16, then FAR fails the depth test on the 4 overlapped
    ("back_to_front", False, 32),  # FAR 16, then NEAR passes everywhere: 4 pixels shaded twice
    ("front_to_back", True, 28),   # pre-pass: one shade per visible pixel, whatever the order
    ("back_to_front", True, 28),
])
def test_two_overlapping_quads(order, prepass, expected):
    parts = [NEAR, FAR] if order == "front_to_back" else [FAR, NEAR]
    c, frame = counts(make_scene(parts), z_prepass=prepass)
    assert c["shade_invocations"] == expected
    assert c["covered_pixels"] == 28
    assert c["fragments"] == 32
    assert set(COUNT_KEYS) <= set(c)
    np.testing.assert_allclose(c["overshading"], expected / 28, rtol=1e-6)
    assert int(frame.aux["shade_count"].sum()) == expected


def test_image_does_not_depend_on_order_or_prepass():
    imgs = [np.asarray(counts(make_scene(p), z_prepass=z)[1].image)
            for p in ([NEAR, FAR], [FAR, NEAR]) for z in (False, True)]
    for img in imgs[1:]:
        np.testing.assert_allclose(img, imgs[0], atol=1e-6)


def test_helper_lanes_of_a_small_triangle():
    # Window corners (1, 1), (4.9, 1), (1, 4.9): centres with x + y < 2.9 inside the offset
    # triangle: (1,1) (2,1) (3,1) (1,2) (2,2) (1,3). Quads (2x2-aligned): (0,0) holds 1 pixel,
    # (1,0) 2, (0,1) 2, (1,1) 1: 4 quads, 16 lanes, 6 shaded, 10 helpers.
    c, frame = counts(make_scene([tri_part([(1, 1), (4.9, 1), (1, 4.9)], 2.0)]))
    expected = np.zeros((H, W), np.int32)
    for x, y in [(1, 1), (2, 1), (3, 1), (1, 2), (2, 2), (1, 3)]:
        expected[y, x] = 1
    np.testing.assert_array_equal(np.asarray(frame.aux["shade_count"]), expected)
    assert (c["shade_invocations"], c["quads"], c["helper_lanes"]) == (6, 4, 10)


def test_four_scattered_pixels_cost_sixteen_lanes():
    # A sliver along y = 1.5 + (x - 1.5) / 2 covers the centres of pixels (1,1), (3,2), (5,3),
    # (7,4): one pixel in each of four quads, so 4 invocations launch 16 lanes.
    c, frame = counts(make_scene([tri_part([(0.9, 1.0), (9.0, 5.25), (0.9, 1.4)], 2.0)]))
    ys, xs = np.nonzero(np.asarray(frame.aux["shade_count"]))
    assert sorted(zip(xs.tolist(), ys.tolist())) == [(1, 1), (3, 2), (5, 3), (7, 4)]
    assert c["shade_invocations"] == 4
    assert c["quads"] * 4 == 16
    assert c["helper_lanes"] == 12


def test_foliage_without_prepass_shades_strictly_more():
    scene = foliage_scene()
    plain, f0 = counts(scene)
    pre, f1 = counts(scene, z_prepass=True)
    assert plain["shade_invocations"] > pre["shade_invocations"]
    assert pre["shade_invocations"] == pre["covered_pixels"]
    assert plain["alpha_invocations"] > 0  # the leaves are alpha-tested
    np.testing.assert_allclose(np.asarray(f0.image), np.asarray(f1.image), atol=1e-6)
    assert FOLIAGE_CARDS > 0


def test_camera_move_does_not_recompile():
    scene = make_scene([NEAR, FAR])
    cfg = make_config("forward", width=W, height=H)
    FORWARD.render(scene, scene.camera, cfg)
    before = program.cache_size()
    moved = jax.tree_util.tree_map(lambda a: a, scene.camera)
    moved = type(moved)(moved.eye + 0.01, moved.rotation, moved.fov_y, moved.near, moved.far)
    FORWARD.render(scene, moved, cfg)
    assert program.cache_size() == before


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="msaa"):
        make_config("forward", msaa=3)
    with pytest.raises(KeyError, match="no parameter"):
        make_config("forward", z_pre_pass=True)


@pytest.mark.parametrize("filled", [0.05, 0.3, 0.9])
def test_the_single_sample_draw_list_is_quad_major_and_in_draw_order(filled):
    # One sample sorts only the filled prefix of its list, by (2x2 quad, triangle, lane); the
    # oracle is NumPy's lexsort of the same fragments.
    from jaxrender.pipelines.forward_draw import single_sample_draw_list
    from jaxrender.raster.fragments import Fragments

    rng = np.random.default_rng(int(filled * 100))
    cap, w, h, n_tris = 4000, 31, 29, 300  # odd sides: quads at the edges are partial
    n = int(cap * filled)
    valid = np.arange(cap) < n
    # Unique (pixel, triangle) pairs, as a fragment list of one sample holds.
    pairs = rng.choice(w * h * n_tris, n, replace=False)
    pixel = np.zeros(cap, np.int32)
    tri = np.full(cap, -1, np.int32)
    pixel[:n], tri[:n] = pairs // n_tris, pairs % n_tris
    depth = np.where(valid, rng.random(cap), 1.0).astype(np.float32)
    fr = Fragments(*(jax.numpy.asarray(a) for a in (pixel, tri, depth, valid)),
                   jax.numpy.int32(n))
    got = single_sample_draw_list(fr, w, h, n_tris)
    x, y = pixel[:n] % w, pixel[:n] // w
    quad, lane = (y // 2) * ((w + 1) // 2) + x // 2, (y % 2) * 2 + x % 2
    order = np.lexsort((lane, tri[:n], quad))
    np.testing.assert_array_equal(np.asarray(got.pixel)[:n], pixel[order], err_msg="pixel")
    np.testing.assert_array_equal(np.asarray(got.tri)[:n], tri[order], err_msg="tri")
    np.testing.assert_array_equal(np.asarray(got.tri)[n:], EMPTY, err_msg="tri of the tail")
    np.testing.assert_array_equal(np.asarray(got.depth)[:n], depth[order], err_msg="depth")
    np.testing.assert_array_equal(np.asarray(got.lane)[:n], lane[order], err_msg="lane")
    np.testing.assert_array_equal(np.asarray(got.valid), valid, err_msg="valid")
    np.testing.assert_array_equal(np.asarray(got.slot), np.where(valid, got.pixel, w * h))
    starts = np.concatenate([[True], quad[order][1:] != quad[order][:-1]])
    np.testing.assert_array_equal(np.asarray(got.seg)[:n], starts, err_msg="seg")


@pytest.mark.parametrize("z_prepass", [False, True])
def test_sorting_and_replaying_in_one_branch_equals_the_two_steps(z_prepass):
    # Without an alpha test nothing runs between the draw list's sort and its depth test, so
    # both run in one branch of the filled prefix: the same draw list and plan as the two
    # steps, on fresh random fragments (a pixel's fragments of many triangles, so that the
    # depth test rejects some), with one host read where the two steps take two.
    from jaxrender.bench import round_trips
    from jaxrender.pipelines.forward_draw import (replay, single_sample_draw_list,
                                                  sorted_and_replayed)
    from jaxrender.raster.fragments import Fragments

    rng = np.random.default_rng(11 + z_prepass)
    cap, w, h, n_tris, n = 3000, 21, 17, 40, 1700
    pairs = rng.choice(w * h * n_tris, n, replace=False)
    valid = np.arange(cap) < n
    pixel, tri = np.zeros(cap, np.int32), np.full(cap, -1, np.int32)
    pixel[:n], tri[:n] = pairs // n_tris, pairs % n_tris
    depth = np.where(valid, rng.random(cap), 1.0).astype(np.float32)
    fr = Fragments(*(jnp.asarray(a) for a in (pixel, tri, depth, valid)), jnp.int32(n))
    cfg = make_config("forward", width=w, height=h, z_prepass=z_prepass)

    def two_steps(f):
        draw = single_sample_draw_list(f, w, h, n_tris)
        return draw, replay(draw, draw.valid, 1, cfg)

    def one_branch(f):
        return sorted_and_replayed(f, n_tris, cfg)

    want, got = two_steps(fr), one_branch(fr)
    paths, want_leaves = zip(*jax.tree_util.tree_flatten_with_path(want)[0])
    got_leaves = jax.tree.leaves(got)
    assert len(got_leaves) == len(want_leaves), "the two results differ in structure"
    for path, a, b in zip(paths, want_leaves, got_leaves):
        np.testing.assert_array_equal(np.asarray(b), np.asarray(a),
                                      err_msg=jax.tree_util.keystr(path))
    assert 0 < int(jnp.sum(got[1][0])) < n, "the depth test rejected nothing or everything"
    reads = [round_trips.count(f, fr).per_frame()[None] for f in (two_steps, one_branch)]
    assert reads == [2, 1], f"host reads (two steps, one branch): {reads}"


def test_a_room_sized_quad_list_sorts_a_32_bit_key_on_a_gpu():
    # (quad, triangle, lane) at 1920x1080 with room's 1056 triangles: 19 + 13 bits with the
    # triangle and lane in one key (one out-of-range code), 33 as three keys; the GPU branch of
    # lex_sort then sorts uint32 keys beside the index instead of uint64 ones.
    from jaxrender.pipelines.forward_draw import single_sample_draw_list
    from jaxrender.raster.fragments import Fragments

    cap = 1 << 16
    fr = Fragments(jax.ShapeDtypeStruct((cap,), np.int32), jax.ShapeDtypeStruct((cap,), np.int32),
                   jax.ShapeDtypeStruct((cap,), np.float32), jax.ShapeDtypeStruct((cap,), bool),
                   jax.ShapeDtypeStruct((), np.int32))
    closed = jax.make_jaxpr(lambda f: single_sample_draw_list(f, 1920, 1080, 1056))(fr)
    dtypes = {str(eqn.invars[0].aval.dtype) for eqn in all_equations(closed.jaxpr)
              if eqn.primitive.name == "sort"}
    assert "uint32" in dtypes and "uint64" not in dtypes, f"sort key dtypes {sorted(dtypes)}"


def test_the_per_pixel_minimum_of_a_quad_major_list():
    # Each pixel's running minimum over its own earlier fragments, its quad's other pixels'
    # interleaved: against a loop over the entries.
    from jaxrender.pipelines.quads import exclusive_lane_cummin

    rng = np.random.default_rng(7)
    n = 500
    quad = np.sort(rng.integers(0, 40, n))
    lane = rng.integers(0, 4, n)
    values = rng.random(n).astype(np.float32)
    start = np.concatenate([[True], quad[1:] != quad[:-1]])
    want = np.full(n, np.inf, np.float32)
    seen = {}
    for i in range(n):
        want[i] = seen.get((quad[i], lane[i]), np.inf)
        seen[(quad[i], lane[i])] = min(want[i], values[i])
    got = exclusive_lane_cummin(jax.numpy.asarray(values), jax.numpy.asarray(start),
                                jax.numpy.asarray(lane, jax.numpy.int32))
    np.testing.assert_array_equal(np.asarray(got), want, err_msg="per-pixel exclusive minimum")


@pytest.mark.parametrize("filled", [0.1, 0.6])
def test_the_quad_list_of_a_filled_prefix_equals_the_full_sort(filled):
    from jaxrender.pipelines.quads import quad_list

    rng = np.random.default_rng(int(filled * 10))
    n, w, h, n_tris = 3000, 40, 30, 200
    live = int(n * filled)
    tri = jax.numpy.asarray(rng.integers(0, n_tris, n), jax.numpy.int32)
    pixel = jax.numpy.asarray(rng.integers(0, w * h, n), jax.numpy.int32)
    shaded = jax.numpy.asarray((rng.random(n) < 0.7) & (np.arange(n) < live))
    want = quad_list(tri, pixel, shaded, w, h, n_tris)
    got = quad_list(tri, pixel, shaded, w, h, n_tris, live=jax.numpy.int32(live))
    for key in want:
        np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]),
                                      err_msg=f"{key} at {filled:.0%}")


def test_the_replay_does_not_depend_on_the_list_capacity():
    """The depth test, quads and shade counts run over the filled prefix of the draw list, in
    a branch chosen by how full it is: capacities that put the same fragments in prefixes of
    different lengths (exactly full, the default, twice it) give the same frame bit for bit."""
    scene = foliage_scene()
    default = FORWARD.render(scene, scene.camera, make_config("forward", width=W, height=H))
    fragments = int(default.counts["fragments"])
    for cap in (fragments, 8 * W * H):
        f = FORWARD.render(scene, scene.camera, make_config(
            "forward", width=W, height=H, fragment_capacity=cap))
        np.testing.assert_array_equal(np.asarray(f.image), np.asarray(default.image),
                                      err_msg=f"image, capacity {cap}")
        np.testing.assert_array_equal(np.asarray(f.aux["shade_count"]),
                                      np.asarray(default.aux["shade_count"]),
                                      err_msg=f"shade counts, capacity {cap}")
        for k, v in default.counts.items():
            assert float(f.counts[k]) == float(v), (cap, k)
