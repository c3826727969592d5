"""Studies render each camera path as one sequence: the stateful pipelines' temporal behaviour
(checkerboard history, object-space store) acts in a study exactly as in a direct
``render_sequence`` call, and the rows report it."""

import json
import textwrap

import numpy as np
import pytest

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.study import backend, programs, runner
from jaxrender.study.schema import load_study

W, H = 32, 18

STUDY = """
name = "sequences"
resolution = "32x18"
metrics = ["rmse", "psnr"]
save_frames = [0, 1, 2, 3]
scenes = [{ name = "spheres", params = { rows = 1, cols = 2, lat = 8, lon = 16 } }]
paths = [{ name = "still", type = "static", frames = 4 },
         { name = "pan", type = "pan", frames = 4, params = { pixels_per_frame = 1.0 } }]
WARMUP

[reference]
params = { k = 2 }
check_convergence = false

[timing]
warmup = 0
repeats = 1
single_frame = false
# The times are not the subject: one program per variant, its counts and views timed too.
outputs = "all"

[[pipelines]]
type = "checkerboard"

[[pipelines]]
type = "checkerboard"
label = "checkerboard_spatial"
params = { temporal = false }

[[pipelines]]
type = "object_space"
params = { reuse = false }

[[pipelines]]
type = "object_space"
label = "object_space_every2"
params = { shade_every = 2, reuse = false }
"""


def _study_text(warmup: int, variants=None) -> str:
    """STUDY with ``warmup`` frames, only the given variant labels if given."""
    text = STUDY.replace("WARMUP", f"warmup_frames = {warmup}")
    if variants is not None:
        head, *blocks = text.split("[[pipelines]]")
        keep = [b for b in blocks if (b.split('label = "')[1].split('"')[0] if 'label = "' in b
                                      else b.split('type = "')[1].split('"')[0]) in variants]
        text = head + "".join("[[pipelines]]" + b for b in keep)
    return text


def _run(tmp_path_factory, text: str):
    """Run the study, keeping every image the runner scored (what its rows describe)."""
    root = tmp_path_factory.mktemp("seq")
    f = root / "study.toml"
    f.write_text(textwrap.dedent(text))
    scored = []
    real = backend.frame_metrics

    def keep(test, ref, names):
        scored.append(np.array(test))
        return real(test, ref, names)

    mp = pytest.MonkeyPatch()
    mp.setenv("JAXRENDER_CACHE", str(root / "cache"))
    mp.setattr(backend, "frame_metrics", keep)
    try:
        study = load_study(f)
        res = runner.run_study(study, root / "run", progress=False, log=lambda *a: None)
    finally:
        mp.undo()
    # run_study scores sequences in plan order: scene, path, variant, frame
    images = {}
    for i, key in enumerate((p.name, v.label, t) for p in study.paths for v in study.variants
                            for t in range(p.frames)):
        images[key] = scored[i]
    return study, res, images, root / "run"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    return _run(tmp_path_factory, _study_text(0))


def _rows(res, pipeline, path):
    rows = [r for r in res.rows if r["pipeline"] == pipeline and r["camera_path"] == path]
    return sorted(rows, key=lambda r: r["frame"])


def _direct(study, label, path_name, warmup=0):
    """render_sequence called directly on the study's scene, cameras and config."""
    spec = study.scenes[0]
    path = next(p for p in study.paths if p.name == path_name)
    v = next(v for v in study.variants if v.label == label)
    scene = backend.load_scene(spec.source, dict(spec.params))
    cams = backend.make_cameras(scene, programs.rendered_path(study, path), W, H)
    cfg = make_config(v.type, width=W, height=H, **dict(v.params))
    pipe = get_pipeline(v.type)
    return pipe, scene, cams, cfg, pipe.render_sequence(scene, cams, cfg, warmup_frames=warmup)


@pytest.mark.parametrize("label", ["checkerboard", "object_space", "object_space_every2"])
def test_study_frames_are_render_sequence_frames(run, label):
    study, res, images, _ = run
    pipe, scene, cams, cfg, seq = _direct(study, label, "pan")
    for t in range(4):
        np.testing.assert_array_equal(images["pan", label, t], np.asarray(seq.image[t]),
                                      err_msg=f"{label}: study frame {t} != render_sequence")
        row = _rows(res, label, "pan")[t]
        for k in ("shade_invocations", "history_reads", "chunks_reused", "shadels_shaded"):
            if k in seq.counts:
                assert row[k] == int(seq.counts[k][t]), (label, k, t)
    one = pipe.render(scene, cams[0], cfg)
    # The single-frame program and the scan body are compiled apart: equal counts and masks,
    # the image equal up to float reassociation.
    for k, v in one.counts.items():
        np.testing.assert_array_equal(np.asarray(v), np.asarray(seq.counts[k][0]),
                                      err_msg=f"{label}: count {k} of render != frame 0")
    np.testing.assert_allclose(np.asarray(one.image), np.asarray(seq.image[0]), atol=1e-3,
                               err_msg=f"{label}: render != frame 0 of render_sequence")


def _shaded(out, label, t):
    for f in sorted(out.glob(f"images/*__still__*__f{t}.npz")):  # find ours by its meta
        with np.load(f) as z:
            if json.loads(str(z["meta"]))["pipeline"] == label:
                return z["aux_shaded"].astype(bool)
    raise AssertionError(f"no saved frame {t} of {label}")


def test_checkerboard_alternates_and_reads_history(run):
    _, res, _, out = run
    masks = [_shaded(out, "checkerboard", t) for t in range(4)]
    for t in range(3):
        both = masks[t] & masks[t + 1]
        # on a still camera the two checkers are complementary; only orphans (covered pixels
        # with no covered neighbour, shaded every frame) may be shaded twice
        orphans = _rows(res, "checkerboard", "still")[t + 1]["orphans_shaded"]
        assert both.sum() <= orphans, (t, int(both.sum()), orphans)
        assert (masks[t] | masks[t + 1]).sum() >= masks[t].sum() * 1.9
    for path in ("still", "pan"):
        temporal = _rows(res, "checkerboard", path)
        spatial = _rows(res, "checkerboard_spatial", path)
        assert temporal[0]["history_reads"] == 0
        assert all(r["history_reads"] > 0 for r in temporal[1:]), [r["history_reads"]
                                                                   for r in temporal]
        assert all(r["history_reads"] == 0 for r in spatial)
    # static camera: the history is exact, so from frame 1 on temporal beats spatial-only
    t_psnr = [r["psnr"] for r in _rows(res, "checkerboard", "still")[1:]]
    s_psnr = [r["psnr"] for r in _rows(res, "checkerboard_spatial", "still")[1:]]
    assert min(t_psnr) > max(s_psnr), (t_psnr, s_psnr)


def test_object_space_shade_every_acts_in_a_study(run):
    _, res, _, _ = run
    for path in ("still", "pan"):
        every1 = _rows(res, "object_space", path)
        every2 = _rows(res, "object_space_every2", path)
        assert every1[0]["shadels_shaded"] == every2[0]["shadels_shaded"] > 0
        for t in (1, 3):  # the in-between frames reuse the store
            assert every2[t]["shadels_shaded"] < 0.25 * every1[t]["shadels_shaded"], \
                (path, t, every1[t]["shadels_shaded"], every2[t]["shadels_shaded"])
            assert every2[t]["chunks_reused"] > 0, (path, t)
        assert every2[2]["shadels_shaded"] > every2[1]["shadels_shaded"]  # shading again
        # without reuse, shade_every = 1 shades every allocated chunk of every frame
        assert all(r["chunks_reused"] == 0 for r in every1), path


def test_warmup_frames_start_history_warm(run, tmp_path_factory):
    study0, res0, images0, _ = run
    study, res, images, _ = _run(tmp_path_factory, _study_text(2, {"checkerboard"}))
    rows = _rows(res, "checkerboard", "pan")
    assert [r["warmup_frames"] for r in rows] == [2] * 4
    assert rows[0]["history_reads"] > 0  # frame 0 now has two frames of history
    _, _, _, _, seq = _direct(study, "checkerboard", "pan", warmup=2)
    for t in range(4):
        np.testing.assert_array_equal(images["pan", "checkerboard", t], np.asarray(seq.image[t]),
                                      err_msg=f"warm-up 2: study frame {t}")
    # the scored cameras are the path's frames 2.., so they differ from the cold run's
    assert not np.array_equal(images["pan", "checkerboard", 0], images0["pan", "checkerboard", 0])
