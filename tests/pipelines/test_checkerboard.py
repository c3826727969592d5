"""Checkerboard: the alternating plan, geometry-aware spatial reconstruction, temporal
reconstruction on a static camera (the full image from the second frame on), rejection,
one compile along a camera path, borders and odd sizes."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.pipelines import checkerboard as cb
from jaxrender.pipelines import deferred, make_config, program
from jaxrender.pipelines.pixel_ids import lod_scaled
from jaxrender.scene import look_at
from jaxrender.scene.camera_path import pan
from tests.pipelines.dacs_scenes import H, W, shapes_scene

# Two compiled programs shade the same points; XLA may fuse the float math differently
# (seen: 1 ulp). Pixels that come from history are compared bit for bit with their source.
_ULP_RTOL = 1e-6


def _cfg(**kw):
    return make_config("checkerboard", width=W, height=H, **kw)


def test_static_camera_temporal_equals_full_image_from_second_frame():
    scene = shapes_scene()
    cam = scene.camera
    ref = np.asarray(deferred.render(scene, cam, make_config("deferred", width=W, height=H)).image)
    seq = cb.render_sequence(scene, [cam] * 3, _cfg())
    img = np.asarray(seq.image)
    shaded = np.asarray(seq.aux["shaded"])
    hist = np.asarray(seq.aux["history"])
    assert img.shape == (3, H, W, 3)
    # half the pixels each frame, alternating; together every pixel
    inv = np.asarray(seq.counts["shade_invocations"])
    assert np.all(inv == W * H // 2) and np.all(shaded[0] ^ shaded[1])
    assert not hist[0].any()
    for t in (1, 2):
        assert np.array_equal(hist[t], ~shaded[t])  # every missing pixel from history
        np.testing.assert_array_equal(img[t][hist[t]], img[t - 1][hist[t]])
        np.testing.assert_allclose(img[t], ref, rtol=_ULP_RTOL, atol=0, err_msg=f"frame {t}")
        assert int(seq.counts["history_reads"][t]) == W * H // 2
        assert int(seq.counts["spatial_reads"][t]) == 0
    assert not np.allclose(img[0], ref)  # frame 0 is spatial only
    # the registered single-frame render is the spatial-only first frame
    one = cb.render(scene, cam, _cfg())
    np.testing.assert_allclose(np.asarray(one.image), img[0], rtol=_ULP_RTOL, atol=1e-7)
    assert int(one.counts["reconstruction_reads"]) == int(seq.counts["spatial_reads"][0])


def test_camera_path_does_not_recompile_and_rejects_history():
    scene = shapes_scene()
    path = pan(scene.camera, 3, 2.0, H)
    seq = cb.render_sequence(scene, path, _cfg())
    size = program.cache_size()
    cb.render_sequence(scene, pan(scene.camera, 3, -1.5, H), _cfg())
    assert program.cache_size() == size
    # a 2-pixel pan: most history is reused, the column entering the screen is rejected
    assert int(seq.counts["history_reads"][1]) > W * H // 4
    assert int(seq.counts["history_rejected"][1]) > 0
    assert np.all(np.isfinite(np.asarray(seq.image)))


def test_spatial_reconstruction_does_not_bleed_across_ids():
    h, w = 6, 7
    ids = jnp.asarray(np.where(np.arange(w)[None, :] < 3, 0, 1).repeat(h, 0), jnp.int32)
    colour = jnp.where((ids == 0)[..., None], 0.2, 0.9) * jnp.ones((h, w, 3), jnp.float32)
    depth = jnp.where(ids == 0, 0.5, 0.6).astype(jnp.float32)
    missing = ~cb.checker_mask(h, w, 0)
    img = jnp.where(missing[..., None], 0.0, colour)  # only the shaded half is known
    ncov = [jnp.asarray(cb.inside(h, w, dy, dx)) for dy, dx in cb.NEIGHBOURS]
    rec = np.asarray(cb._spatial(img, ids, depth, ncov))
    m = np.asarray(missing)
    # the mean of 1-4 equal values: exact up to rounding of the division
    np.testing.assert_allclose(rec[m], np.asarray(colour)[m], rtol=_ULP_RTOL)


def test_lone_pixel_is_shaded():
    # a 1x1 image whose pixel is off the checker has no neighbour to rebuild it from
    scene = shapes_scene()
    f = cb.render(scene, scene.camera, make_config("checkerboard", width=1, height=1, frame=1))
    assert int(f.counts["orphans_shaded"]) == 1 and int(f.counts["shade_invocations"]) == 1
    np.testing.assert_array_equal(np.asarray(f.aux["shaded"]), [[True]])
    assert np.all(np.isfinite(np.asarray(f.image)))


def test_odd_size_sequence_with_2x1_pattern_and_lod_bias_is_finite():
    scene = shapes_scene()
    cams = [scene.camera, look_at((0.2, 0.1, 0.0), (0.1, 0.0, -1.0), fov_y_deg=90.0)]
    cfg = make_config("checkerboard", width=W - 1, height=H - 1, pattern="2x1", lod_bias=-1.0)
    seq = cb.render_sequence(scene, cams, cfg)
    assert np.all(np.isfinite(np.asarray(seq.image)))
    assert int(seq.counts["shade_invocations"][0]) in ((W - 1) * (H - 1) // 2,
                                                        (W - 1) * (H - 1) // 2 + 1)


def test_lod_scaling_and_config_errors():
    from jaxrender.types import SurfacePoints
    z = jnp.zeros((2, 3), jnp.float32)
    pts = SurfacePoints(z, z, z, jnp.zeros((2, 4)), jnp.zeros((2, 2)), jnp.ones((2, 2)),
                        jnp.ones((2, 2)), z, jnp.zeros(2, jnp.int32), jnp.zeros(2, jnp.int32),
                        jnp.ones(2, bool))
    s = lod_scaled(pts, 2.0 * 0.5, 0.5)  # 2x1 pattern with LOD bias -1
    np.testing.assert_array_equal(np.asarray(s.duv_dx), 1.0)
    np.testing.assert_array_equal(np.asarray(s.duv_dy), 0.5)
    for bad in ({"pattern": "3x1"}, {"ids": "colour"}, {"depth_tolerance": 0.0}):
        with pytest.raises(ValueError):
            _cfg(**bad)


def test_checker_mask_alternates_with_traced_frame():
    m = jax.jit(lambda t: cb.checker_mask(3, 5, t))
    a, b = np.asarray(m(jnp.int32(4))), np.asarray(m(jnp.int32(7)))
    assert a[0, 0] and not b[0, 0] and np.all(a ^ b)
