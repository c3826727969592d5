"""VRS from screen-space speed, camera motion included: rates per 8x8 tile from motion vectors."""

import jax.numpy as jnp
import numpy as np
import pytest
from fdv_scenes import H, W, make_scene, rect_part

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines.vrs import motion_rates
from jaxrender.scene.camera_path import pan


def test_a_tile_takes_the_rate_of_its_slowest_covered_pixel():
    # 16 x 24: six tiles of 8x8. Thresholds (1, 5) pixels per frame.
    motion = np.zeros((16, 24, 2), np.float32)
    covered = np.ones((16, 24), bool)
    motion[:8, :8] = (0.5, 0.0)     # slow: 1x1 (code 0)
    motion[:8, 8:16] = (3.0, 0.0)   # horizontal, between the thresholds: 2x1 (code 2)
    motion[:8, 16:] = (0.0, -3.0)   # vertical: 1x2 (code 1)
    motion[8:, :8] = (6.0, 2.0)     # fast: 2x2 (code 3) ...
    motion[8:, 8:16] = (6.0, 0.0)
    motion[12, 12] = (0.1, 0.0)     # ... but one slow pixel keeps this tile at 1x1
    motion[8:, 16:] = (6.0, 0.0)
    motion[9, 17] = (0.0, 0.0)
    covered[9, 17] = False          # an empty pixel does not hold its tile back
    got = np.asarray(motion_rates(jnp.asarray(motion), jnp.asarray(covered), (1.0, 5.0)))
    want = np.zeros((16, 24), np.int32)
    want[:8, 8:16], want[:8, 16:], want[8:, :8], want[8:, 16:] = 2, 1, 3, 3
    want[9, 17] = 0  # uncovered: 1x1
    np.testing.assert_array_equal(got, want)


@pytest.fixture(scope="module")
def panned():
    """A static wall over the whole screen seen from a camera panning 2 pixels a frame."""
    scene = make_scene([rect_part(-W, -H, 2 * W, 2 * H, 3.0)])
    path = pan(scene.camera, 3, 2.0, H)
    vb = get_pipeline("visbuffer")
    run = lambda **p: vb.render_sequence(scene, path, make_config(  # noqa: E731
        "visbuffer", width=W, height=H, **p))
    return run(vrs="motion", vrs_thresholds=(1.0, 50.0)), run(vrs="speed",
                                                              vrs_thresholds=(1.0, 50.0))


def test_camera_motion_coarsens_the_rate(panned):
    motion, speed = panned
    rate = np.asarray(motion.aux["rate"])
    covered = np.asarray(motion.counts["covered_pixels"])
    np.testing.assert_array_equal(covered, W * H)
    # Frame 0 has no previous camera: no motion, full rate; then the pan is 2 px/frame
    # horizontally: 2x1 everywhere.
    np.testing.assert_array_equal(rate[0], 0)
    np.testing.assert_array_equal(rate[1:], 2)
    np.testing.assert_array_equal(np.asarray(motion.counts["shade_invocations"]),
                                  [W * H, W * H // 2, W * H // 2])
    # The scene itself is still: the per-triangle speed rule (scene velocity) sees nothing.
    np.testing.assert_array_equal(np.asarray(speed.aux["rate"]), 0)
