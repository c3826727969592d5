"""Forward's waves as hardware packs them: quads of one draw, in rasterization order."""

import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.draw_waves import draw_waves
from jaxrender.pipelines.quads import quad_list

W = H = 16


def _units(quads_of_triangle: dict[int, int]):
    """(tri, pixel) units: triangle t shades every pixel of its first n quads of its own row
    of quads (quad row t), lane 0 only except the first quad (all four lanes)."""
    tri, pix = [], []
    for t, n in quads_of_triangle.items():
        for q in range(n):
            x, y = 2 * q, 2 * t
            lanes = [(0, 0), (1, 0), (0, 1), (1, 1)] if q == 0 else [(0, 0)]
            for dx, dy in lanes:
                tri.append(t)
                pix.append((y + dy) * W + x + dx)
    return np.array(tri, np.int32), np.array(pix, np.int32)


def test_quads_of_one_draw_fill_waves_and_a_new_draw_starts_a_new_wave():
    # Draw 0 = triangles 0 and 1 (5 + 4 quads), draw 1 = triangle 2 (8 quads), draw 2 =
    # triangle 3 (1 quad). Waves of 32 lanes hold 8 quads: draw 0 takes 2 waves (8 + 1),
    # draw 1 one, draw 2 one: 4 waves for 18 quads, where 18 quads packed screen-wide by
    # material (one material) would take 3.
    tri, pix = _units({0: 5, 1: 4, 2: 8, 3: 1})
    tri_object = jnp.asarray([0, 0, 1, 2], jnp.int32)
    pad = 7  # unshaded entries after the shaded ones, as a fragment list has
    tri_p = np.concatenate([tri, np.zeros(pad, np.int32)])
    pix_p = np.concatenate([pix, np.zeros(pad, np.int32)])
    shaded = np.concatenate([np.ones(len(tri), bool), np.zeros(pad, bool)])
    ql = quad_list(jnp.asarray(tri_p), jnp.asarray(pix_p), jnp.asarray(shaded), W, H, 4)
    inv = jnp.int32(len(tri))
    assert int(ql["n_quads"]) == 18
    got = draw_waves(tri_object, ql["start"], ql["tri"], 32, inv)
    assert int(got["waves"]) == 4
    assert int(got["unfilled_lanes"]) == 4 * 32 - 18 * 4
    np.testing.assert_allclose(float(got["lane_utilization"]), len(tri) / (4 * 32), rtol=1e-6)
    # Waves of 64 (16 quads): draw 0 one wave (9 quads), draw 1 one, draw 2 one.
    assert int(draw_waves(tri_object, ql["start"], ql["tri"], 64, inv)["waves"]) == 3
    # One draw for all: 18 quads in 3 waves of 32.
    one = draw_waves(jnp.zeros(4, jnp.int32), ql["start"], ql["tri"], 32, inv)
    assert int(one["waves"]) == 3 and int(one["unfilled_lanes"]) == 3 * 32 - 72


def test_quads_of_a_quad_major_list_equal_the_sorted_quad_list():
    # Forward's one-sample draw list is ordered by (quad, triangle, lane): its quads, counted
    # without a second sort, and their waves equal those of the (triangle, quad) sorted list.
    from jaxrender.pipelines.quads import first_units_of_quads

    rng = np.random.default_rng(11)
    n_tris, n = 40, 1500
    pairs = rng.choice(W * H * n_tris, n, replace=False)  # unique (pixel, triangle) units
    pix, tri = (pairs // n_tris).astype(np.int32), (pairs % n_tris).astype(np.int32)
    shaded = rng.random(n) < 0.6
    x, y = pix % W, pix // W
    quad, lane = (y // 2) * (W // 2) + x // 2, (y % 2) * 2 + x % 2
    order = np.lexsort((lane, tri, quad))
    starts = np.concatenate([[True], quad[order][1:] != quad[order][:-1]])
    first = first_units_of_quads(jnp.asarray(tri[order]), jnp.asarray(starts),
                                 jnp.asarray(shaded[order]))
    ql = quad_list(jnp.asarray(tri), jnp.asarray(pix), jnp.asarray(shaded), W, H, n_tris)
    assert int(jnp.sum(first)) == int(ql["n_quads"]) > 0
    want_units = {(t, q) for t, q, s in zip(tri, quad, shaded) if s}
    got_units = {(int(t), int(q)) for t, q in zip(tri[order][np.asarray(first)],
                                                   quad[order][np.asarray(first)])}
    assert got_units == want_units, "one marked unit for each shaded (triangle, quad)"
    tri_draw = jnp.asarray(np.arange(n_tris) // 7, jnp.int32)  # draws of 7 triangles
    inv = jnp.int32(int(shaded.sum()))
    for wave in (32, 64):
        a = draw_waves(tri_draw, first, jnp.asarray(tri[order]), wave, inv)
        b = draw_waves(tri_draw, ql["start"], ql["tri"], wave, inv)
        for key in a:
            np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]), err_msg=key)
