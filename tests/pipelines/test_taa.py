"""Temporal anti-aliasing, the one temporal resolve every pipeline can add: convergence towards
the supersampled reference, rejection at a disocclusion, nothing compiled without it, and its
settings refused where they are wrong or would do nothing."""

import dataclasses
import re

import numpy as np
import pytest

from jaxrender.metrics import psnr, to_display
from jaxrender.pipelines import RenderConfig, get_pipeline, list_pipelines, make_config, program
from jaxrender.pipelines.taa import from_ycocg, jitter_offsets, sample_history, to_ycocg
from jaxrender.scene.camera_path import pan, stack
from jaxrender.shading import load_lit_scene
from tests.pipelines.motion_scenes import sliding_scene

W, H = 32, 24
# Measured (spheres 1x2 at 32x24, still camera, deferred, bilinear history, clamp): the plain
# frame is 22.5 dB against the k = 4 reference, TAA's frame 31 is 26.2 dB (frames 8 to 31 stay
# within 26.2 to 26.7 dB as the jitter phases cycle). Asserted with a margin of 0.5 dB, and at
# least 3 dB over the plain frame.
TAA_PSNR_32 = 26.2
MARGIN_DB = 0.5


def _builtins():
    return [p for p in list_pipelines() if p.config_cls.__module__.startswith("jaxrender.")]


def test_every_pipeline_takes_taa():
    for pipe in _builtins():
        cfg = make_config(pipe, width=W, height=H, taa=True, taa_alpha=0.2, taa_phases=16,
                          taa_history="catmull_rom", taa_clip="variance")
        assert cfg.taa and cfg.taa_alpha == 0.2, pipe.name


@pytest.mark.parametrize("params, key", [
    ({"taa": True, "taa_alpha": 0.0}, "taa_alpha"),
    ({"taa": True, "taa_alpha": 1.5}, "taa_alpha"),
    ({"taa": True, "taa_clip": "box"}, "taa_clip"),
    ({"taa": True, "taa_history": "nearest"}, "taa_history"),
    ({"taa": True, "taa_phases": 4}, "taa_phases"),
    ({"taa_alpha": 0.5}, "taa_alpha"),  # accepted and ignored without taa: refused
    ({"taa_clip": "variance"}, "taa_clip"),
])
def test_bad_taa_settings_are_refused_naming_the_key(params, key):
    for name in ("deferred", "reference"):
        with pytest.raises(ValueError, match=key):
            make_config(name, width=W, height=H, **params)
    make_config("deferred", width=W, height=H, taa=True, taa_alpha=1.0)  # the bound is in


def test_without_taa_no_jitter_or_history_is_compiled():
    scene = load_lit_scene("spheres", rows=1, cols=1, lat=4, lon=8)
    cams = stack([scene.camera] * 2)

    def hlo(**kw):
        lowered, _ = program.lower(get_pipeline("forward"), scene, cams,
                                   make_config("forward", width=W, height=H, **kw),
                                   sequence=True)
        return lowered.as_text(debug_info=True)

    plain, taa = hlo(), hlo(taa=True)
    for scope in ("taa_jitter", "taa", "taa_history", "motion_vectors"):
        ops = re.compile(r'loc\("([^"]*/)?' + scope + "/")  # an op's named-scope path
        assert not ops.search(plain), f"forward without taa compiles {scope}"
        assert ops.search(taa), f"forward with taa lacks {scope}"


def test_still_scene_converges_towards_the_reference():
    scene = load_lit_scene("spheres", rows=1, cols=2, lat=8, lon=16)
    ref = get_pipeline("reference").render(scene, scene.camera,
                                           make_config("reference", width=W, height=H, k=4))
    deferred = get_pipeline("deferred")
    plain = deferred.render(scene, scene.camera, make_config("deferred", width=W, height=H))
    seq = deferred.render_sequence(scene, stack([scene.camera] * 32),
                                   make_config("deferred", width=W, height=H, taa=True))
    db = lambda img: float(np.asarray(psnr(to_display(img), to_display(ref.image))))  # noqa: E731
    plain_db, taa_db = db(plain.image), db(seq.image[31])
    assert taa_db >= TAA_PSNR_32 - MARGIN_DB, f"TAA after 32 frames: {taa_db:.2f} dB"
    assert taa_db >= plain_db + 3.0, f"TAA {taa_db:.2f} dB vs plain {plain_db:.2f} dB"
    reads = np.asarray(seq.counts["taa_history_reads"])
    assert reads[0] == 0 and np.all(reads[1:] == W * H), "history is read from frame 1 on"


def test_history_is_rejected_at_a_disocclusion():
    scene = sliding_scene()
    cfg = make_config("deferred", width=32, height=24, taa=True)
    seq = get_pipeline("deferred").render_sequence(scene, stack([scene.camera] * 3), cfg)
    rejected = np.asarray(seq.aux["taa_rejected"][2])
    counts = np.asarray(seq.counts["taa_rejections"])
    assert counts[0] == 0 and counts[2] == rejected.sum()
    # The quad slides 2 px right per frame: a 2-column strip of wall behind its left edge is
    # uncovered. Its rows are those the quad covers.
    quad_rows = np.flatnonzero(np.any(rejected, axis=1))
    assert len(quad_rows) >= 8, "the uncovered strip must be rejected along the quad's edge"
    assert rejected.sum() <= 4 * len(quad_rows) + 8, "rejections away from the disocclusion"


def test_halton_jitter_and_colour_space():
    offs = jitter_offsets(16)
    assert np.all(np.abs(offs) < 0.5) and np.allclose(offs[:8], jitter_offsets(8))
    np.testing.assert_allclose(offs[:3], [[0.0, -1 / 6], [-0.25, 1 / 6], [0.25, -7 / 18]],
                               atol=1e-6, err_msg="Halton(2, 3) minus 0.5")
    rgb = np.random.default_rng(0).uniform(0, 1, (5, 3)).astype(np.float32)
    np.testing.assert_allclose(np.asarray(from_ycocg(to_ycocg(rgb))), rgb, atol=1e-6,
                               err_msg="YCoCg round trip")
    img = np.random.default_rng(1).uniform(0, 1, (6, 7, 3)).astype(np.float32)
    centres = np.stack(np.meshgrid(np.arange(7) + 0.5, np.arange(6) + 0.5), -1).astype(np.float32)
    for kind in ("bilinear", "catmull_rom"):
        np.testing.assert_allclose(np.asarray(sample_history(img, centres, kind)), img,
                                   atol=1e-6, err_msg=f"{kind} at pixel centres")


# Each TAA setting changes the output (nothing accepted and ignored): one compiled sequence per
# setting, so these run with the parameter audit (``-m slow``).
CHANGED = {"taa_alpha": 0.5, "taa_phases": 16, "taa_history": "catmull_rom",
           "taa_clip": "variance"}


def test_changed_covers_every_taa_setting():
    fields = {f.name for f in dataclasses.fields(RenderConfig) if f.name.startswith("taa_")}
    assert set(CHANGED) == fields


@pytest.mark.slow
@pytest.mark.parametrize("field", sorted(CHANGED))
def test_each_taa_setting_changes_the_output(field):
    scene = load_lit_scene("spheres", rows=1, cols=2, lat=6, lon=12)
    # A slow pan, past 8 frames (16 phases differ from 8): motion vectors exclude the jitter,
    # so under a still camera the history is read at pixel centres, where every history
    # filter returns the texel itself, and taa_history changes nothing there.
    cams = pan(scene.camera, 10, pixels_per_frame=0.37, height=16)
    run = lambda **kw: np.asarray(get_pipeline("deferred").render_sequence(  # noqa: E731
        scene, cams, make_config("deferred", width=24, height=16, taa=True, **kw)).image)
    assert np.abs(run() - run(**{field: CHANGED[field]})).max() > 1e-4, field


def test_taa_reuses_the_pipelines_visibility(name="deferred"):
    # With the pipeline's buffer handed over the resolve rasterizes nothing of its own, and the
    # frames equal those of a resolve that rasterizes the frame again (the same exact raster).
    from jaxrender.pipelines.visibility import SHARED_VISIBILITY

    scene = sliding_scene()
    pipe = get_pipeline(name)
    cfg = make_config(name, width=W, height=H, taa=True)
    hidden = dataclasses.replace(pipe, step=_without_shared_visibility(pipe.step))
    cams = stack([scene.camera] * 3)
    shared, own = pipe.render_sequence(scene, cams, cfg), hidden.render_sequence(scene, cams, cfg)
    for t in range(3):
        np.testing.assert_array_equal(np.asarray(shared.image[t]), np.asarray(own.image[t]),
                                      err_msg=f"{name}: frame {t} differs with the shared buffer")
    assert SHARED_VISIBILITY not in shared.aux, "the shared buffer must not leave the program"

    def rasterizations(p):
        lowered, _ = program.lower(p, scene, cams, cfg, sequence=True)
        return lowered.as_text().count("_rasterize_impl")

    assert rasterizations(pipe) < rasterizations(hidden), \
        f"{name} with TAA still rasterizes the frame a second time"


def _without_shared_visibility(step):
    from jaxrender.pipelines.visibility import SHARED_VISIBILITY

    def hidden(scene, static, state, camera, t, cfg):
        frame, state = step(scene, static, state, camera, t, cfg)
        aux = {k: v for k, v in frame.aux.items() if k != SHARED_VISIBILITY}
        return dataclasses.replace(frame, aux=aux), state

    return hidden
