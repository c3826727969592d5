"""Deferred shading: agreement with forward and visbuffer, G-buffer bytes, one shade per pixel."""

import numpy as np
from fdv_scenes import H, W, make_scene, rect_part

from jaxrender.pipelines import COUNT_KEYS, get_pipeline, make_config
from jaxrender.pipelines.gbuffer import DEPTH_BYTES, GBUFFER_CHANNELS

_ATOL = 1e-5  # float32 shading of identical points; only summation order may differ


def no_overdraw_scene():
    # Two non-overlapping rectangles with bent normals (shading varies), nothing alpha-tested.
    return make_scene([rect_part(1, 1, 13, 11, 2.0, tilt=0.6),
                       rect_part(15, 4, 30, 22, 5.0, tilt=-0.4)])


def render(name, scene, **params):
    return get_pipeline(name).render(scene, scene.camera,
                                     make_config(name, width=W, height=H, **params))


def test_forward_deferred_visbuffer_agree_without_overdraw():
    scene = no_overdraw_scene()
    frames = {n: render(n, scene) for n in ("forward", "deferred", "visbuffer")}
    ref = np.asarray(frames["forward"].image)
    assert ref.max() > 0.05 and np.unique(ref.round(4).reshape(-1, 3), axis=0).shape[0] > 20
    for name, f in frames.items():
        np.testing.assert_allclose(np.asarray(f.image), ref, atol=_ATOL, rtol=_ATOL,
                                   err_msg=f"mismatch: {name}")
        assert set(COUNT_KEYS) <= set(f.counts), name
        assert int(f.counts["covered_pixels"]) == 12 * 10 + 15 * 18, name
        assert int(f.counts["shade_invocations"]) == 12 * 10 + 15 * 18, name


def test_gbuffer_bytes_from_layout():
    scene = make_scene([rect_part(0, 0, 4, 4, 2.0), rect_part(2, 2, 6, 6, 4.0)])
    f = render("deferred", scene)
    c = {k: int(v) for k, v in f.counts.items() if "util" not in k and k != "overshading"}
    assert c["covered_pixels"] == 28 and c["shade_invocations"] == 28
    assert c["helper_lanes"] == 0
    assert c["gbuffer_bytes_written"] == 28 * (GBUFFER_CHANNELS * 4 + DEPTH_BYTES)
    assert c["gbuffer_bytes_read"] == 28 * GBUFFER_CHANNELS * 4
    assert c["bytes_intermediate"] == c["gbuffer_bytes_written"] + c["gbuffer_bytes_read"]
