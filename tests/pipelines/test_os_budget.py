"""Object-space MIP-bias budget feedback across frames (issue 22, os_budget) and the store's
bookkeeping in bits per shadel (os_memory).

The plane of test_object_space fills a 32x32 view with a 32^2 sheet (1 shadel per pixel, LOD 0
everywhere at distance D; LOD 1 at 2D, where it covers 16x16 pixels). Its MIP levels hold 16,
4 and 1 chunks, so the chunks a bias b marks are hand-worked: trilinear reads levels floor(b)
and floor(b) + 1 (the second only at a non-zero fraction), clamped at level 2.
"""

from __future__ import annotations

import functools
import re

import numpy as np
import pytest

from jaxrender.pipelines import get_pipeline, make_config, program
from jaxrender.pipelines import object_space as osp
from jaxrender.pipelines.os_memory import bits
from jaxrender.pipelines.os_sheet import LANES, build_sheet
from jaxrender.scene import look_at
from tests.pipelines.test_object_space import D, H, W, plane_scene

STORE = 6  # chunks: fewer than level 0 needs (16), more than level 1 (4) or levels 1 + 2 (5)
CLOSE, FAR = 8, 6  # frames at distance D, then at 2D
STEP, RELAX, LOW = 0.25, 0.0625, 0.8  # bias_step, and bias_relax, bias_low (the defaults)


def _camera(d):
    return look_at((0.0, 0.0, d), (0.0, 0.0, 0.0), fov_y_deg=90.0, near=0.1, far=20.0)


def _cfg(**kw):
    return osp.ObjectSpaceConfig(width=W, height=H, sheet_resolution=W, **kw)


@functools.lru_cache(maxsize=None)
def close_then_far():
    cams = [_camera(D)] * CLOSE + [_camera(2 * D)] * FAR
    cfg = _cfg(store_shadels=STORE * LANES, bias_feedback=True)
    f = osp.render_sequence(plane_scene(), cams, cfg)
    return f, {k: np.asarray(v) for k, v in f.counts.items()}


def test_bias_rises_over_frames_when_the_store_is_too_small_and_relaxes_when_freed():
    f, c = close_then_far()
    # Hand-worked, frame by frame (requested chunks at the frame's bias; store 6, low 4.8):
    # close: 0 -> level 0 (16 > 6: raise); .25, .5, .75 -> levels 0 + 1 (20: raise); 1 -> level
    # 1 (4 < 4.8: relax); .9375 -> levels 0 + 1 (20: raise); 1.1875 -> levels 1 + 2 (5: hold).
    # far (LOD 1): 1.1875 .. 1 -> level 2 (1 < 4.8: relax by 1/16 a frame); .9375 -> levels 1
    # + 2 (5: hold).
    bias = [0.0, 0.25, 0.5, 0.75, 1.0, 0.9375, 1.1875, 1.1875,
            1.1875, 1.125, 1.0625, 1.0, 0.9375, 0.9375]
    requested = [16, 20, 20, 20, 4, 20, 5, 5, 1, 1, 1, 1, 5, 5]
    np.testing.assert_array_equal(c["mip_bias"], bias, err_msg="bias per frame")
    np.testing.assert_array_equal(c["chunks_requested"], requested, err_msg="chunks requested")
    # Over budget, the coarsest chunk comes first, then coarse to fine: frame 0 holds level 2
    # and 5 of 16 level-0 chunks (11 unshaded, 1024 - 5 * 64 pixels fall back); frames with
    # levels 0 + 1 hold level 2, all of level 1 and one level-0 chunk (15 unshaded, 960).
    over = np.asarray(requested) > STORE
    np.testing.assert_array_equal(c["chunks_allocated"], np.where(over, STORE, requested))
    np.testing.assert_array_equal(c["chunks_unshaded"], [11, 15, 15, 15, 0, 15] + [0] * 8)
    np.testing.assert_array_equal(c["fallback_pixels"], [704, 960, 960, 960, 0, 960] + [0] * 8)
    assert np.all(c["overflow"] == 0) and np.all(c["missing_taps"] == 0)
    assert np.all(np.isfinite(np.asarray(f.image)))
    # The rule itself, as NumPy (within the thresholds): raise over the store, relax below
    # bias_low of it, never below mip_bias; the next frame starts where this one ended.
    req, b = c["chunks_requested"].astype(np.float64), c["mip_bias"]
    want = np.where(req > STORE, b + STEP, np.where(req < LOW * STORE, b - RELAX, b))
    np.testing.assert_array_equal(c["mip_bias_next"], np.maximum(want, 0.0))
    np.testing.assert_array_equal(c["mip_bias"][1:], c["mip_bias_next"][:-1])
    # What the issue asks, in words: rising while over budget, falling once the view frees it.
    assert np.all(np.diff(b[:5]) == STEP) and b[CLOSE - 1] > b[0]
    assert np.all(np.diff(b[CLOSE:CLOSE + 5]) == -RELAX)


def test_pixels_of_unshaded_chunks_read_the_coarsest_level():
    # Frame 0 of the close view: 704 pixels fell back to level 2, whose one chunk is resident;
    # they show exactly what a render at level 2 everywhere shows (a bias past the top level,
    # the plain in-frame allocation).
    f, c = close_then_far()
    lvl = np.asarray(f.aux["mip_level"][0])
    fell = lvl == 2.0
    assert int(fell.sum()) == int(c["fallback_pixels"][0])
    coarse = osp.render(plane_scene(), _camera(D), _cfg(mip_bias=2.0))
    np.testing.assert_array_equal(np.asarray(f.image[0])[fell], np.asarray(coarse.image)[fell],
                                  err_msg="fallback pixels != the coarsest level")
    assert np.all(lvl[~fell] == 0.0), "the other pixels read level 0 at bias 0"


def test_within_budget_feedback_allocates_as_the_in_frame_retry():
    # A store that holds everything: the bias never rises (it relaxes to its floor, mip_bias)
    # and the frames equal the plain pipeline's, bit for bit.
    cams = [_camera(D), _camera(2 * D), _camera(2 * D)]
    plain = osp.render_sequence(plane_scene(), cams, _cfg())
    fb = osp.render_sequence(plane_scene(), cams, _cfg(bias_feedback=True))
    np.testing.assert_array_equal(np.asarray(fb.image), np.asarray(plain.image))
    for k, v in plain.counts.items():
        np.testing.assert_array_equal(np.asarray(fb.counts[k]), np.asarray(v), err_msg=k)
    assert np.all(np.asarray(fb.counts["mip_bias"]) == 0.0)
    assert np.all(np.asarray(fb.counts["chunks_unshaded"]) == 0)


def test_without_feedback_none_of_it_is_compiled():
    cams = program.stack_cameras([_camera(D)] * 2)
    scope = re.compile(r'loc\("([^"]*/)?bias_feedback/')

    def hlo(**kw):
        lowered, _ = program.lower(get_pipeline("object_space"), plane_scene(), cams, _cfg(**kw),
                                   sequence=True)
        return lowered.as_text(debug_info=True)

    assert not scope.search(hlo()), "object_space without bias_feedback compiles it"
    assert scope.search(hlo(bias_feedback=True)), "the feedback's scope is not in its program"


@pytest.mark.parametrize("params,key", [
    ({"bias_low": 0.5}, "bias_low"),  # accepted and ignored without bias_feedback: refused
    ({"bias_relax": 0.125}, "bias_relax"),
    ({"bias_feedback": True, "bias_low": 0.0}, "bias_low"),
    ({"bias_feedback": True, "bias_low": 1.5}, "bias_low"),
    ({"bias_feedback": True, "bias_relax": 0.0}, "bias_relax"),
])
def test_bad_feedback_settings_are_refused_naming_the_key(params, key):
    with pytest.raises(ValueError, match=key):
        make_config("object_space", **params)
    make_config("object_space", bias_feedback=True, bias_low=1.0, bias_relax=0.5)


def test_bits_per_shadel_are_the_arrays_sizes():
    f, c = close_then_far()
    sheet = build_sheet(plane_scene(), _cfg())
    shadels = sheet.n_chunks * LANES  # 21 chunks: 16 + 4 + 1
    assert sheet.n_chunks == 21 and int(c["virtual_shadels"][0]) == shadels
    # The owner map: one int32 per virtual shadel.
    np.testing.assert_allclose(c["id_map_bits_per_shadel"], 32.0, err_msg="ID map bits")
    assert bits(sheet.owner) == 32 * shadels
    # Per chunk: object, level, x, y and the page entry (5 int32), per store slot its chunk.
    meta = (5 * 32 * sheet.n_chunks + 32 * STORE) / shadels
    np.testing.assert_allclose(c["chunk_metadata_bits_per_shadel"], meta, rtol=1e-6,
                               err_msg="chunk metadata bits")
    # The MIP chain's size over level 0: 21 / 16 chunks.
    np.testing.assert_allclose(c["mip_chain_memory"], 21 / 16, err_msg="MIP chain overhead")


def test_store_per_pixel_sizes_the_store_in_shadels_per_pixel():
    # 1.5 x 32 x 32 = 1536 shadels = 24 chunks; 1 per pixel = the store_shadels of W x H.
    assert _cfg(store_per_pixel=1.5).store_chunks == 24
    assert _cfg(store_per_pixel=1.0).store_chunks == _cfg(store_shadels=W * H).store_chunks
    assert _cfg(store_per_pixel=0.01).store_chunks == 1  # rounded up to whole chunks
    with pytest.raises(ValueError, match="store_shadels"):
        _cfg(store_per_pixel=2.0, store_shadels=4096)
