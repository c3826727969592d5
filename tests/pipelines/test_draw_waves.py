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
    got = draw_waves(tri_object, ql, 32, inv)
    assert int(got["waves"]) == 4
    assert int(got["unfilled_lanes"]) == 4 * 32 - 18 * 4
    np.testing.assert_allclose(float(got["lane_utilization"]), len(tri) / (4 * 32), rtol=1e-6)
    # Waves of 64 (16 quads): draw 0 one wave (9 quads), draw 1 one, draw 2 one.
    assert int(draw_waves(tri_object, ql, 64, inv)["waves"]) == 3
    # One draw for all: 18 quads in 3 waves of 32.
    one = draw_waves(jnp.zeros(4, jnp.int32), ql, 32, inv)
    assert int(one["waves"]) == 3 and int(one["unfilled_lanes"]) == 3 * 32 - 72
