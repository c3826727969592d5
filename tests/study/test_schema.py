"""Study files: valid ones resolve as documented; each malformed one gives its own error,
naming the file and the key path."""

import textwrap

import pytest

from jaxrender.errors import StudyError, UserError
from jaxrender.parsing import parse_resolution
from jaxrender.study.schema import load_study
from jaxrender.study.specs import to_toml

from tests.study.doubles import MINIMAL_STUDY as BASE
from tests.study.doubles import write_study as _write


def test_minimal_defaults(fake):
    s = load_study(_write(fake, BASE))
    assert s.resolution == (24, 16)
    assert [p.type for p in s.paths] == ["static"] and s.paths[0].frames == 1
    assert [v.params for v in s.variants] == [()]
    assert s.reference.pipeline == "reference"
    assert "psnr" in s.metrics and "summary_table" in s.figures


def test_sweeps_cartesian_and_zip(fake):
    s = load_study(_write(fake, BASE + """
        sweep = { levels = [2, 4, 8], noise = [0.0, 0.1] }
        [[pipelines]]
        type = "flat"
        label = "zipped"
        params = { dither = true }
        sweep = { levels = [2, 4], noise = [0.0, 0.1] }
        sweep_mode = "zip"
        """))
    cart = [dict(v.params) for v in s.variants if v.label == "flat"]
    assert len(cart) == 6 and {"levels": 8, "noise": 0.1} in cart
    assert all(isinstance(v["noise"], float) for v in cart)  # ints widened for float fields
    zipped = [dict(v.params) for v in s.variants if v.label == "zipped"]
    assert zipped == [{"dither": True, "levels": 2, "noise": 0.0},
                      {"dither": True, "levels": 4, "noise": 0.1}]


def test_presets_compose(fake):
    s = load_study(_write(fake, """
        scenes = [{ name = "tiny2", params = { n = 3 } }, "tiny"]
        frames = 5
        paths = ["slowpan", { preset = "slowpan", name = "long", frames = 7 }]
        [[pipelines]]
        preset = "coarse"
        params = { noise = 0.5 }
        """))
    assert [(p.name, p.type, p.frames) for p in s.paths] == [("slowpan", "fakepan", 3),
                                                             ("long", "fakepan", 7)]
    assert dict(s.paths[0].params) == {"step": 0.02}
    assert s.variants[0].label == "coarse"
    assert dict(s.variants[0].params) == {"levels": 2, "noise": 0.5}
    assert s.scenes[0].params == (("n", 3),)


def test_orbit_center_over_a_preset_that_sets_distance(fake):
    """A preset's distance gives way to the entry's own center (the one that would be
    ignored is dropped); both in the entry itself are refused (MALFORMED)."""
    (fake / "configs" / "paths" / "round.toml").write_text(
        'type = "orbit"\n[params]\ndegrees_per_frame = 2.0\ndistance = 3.0\n')
    s = load_study(_write(fake, BASE + '[[paths]]\npreset = "round"\n'
                          'params = { center = [0, 1, 0] }\n'))
    assert dict(s.paths[0].params) == {"degrees_per_frame": 2.0, "center": (0, 1, 0)}


def test_overrides_and_round_trip(fake, tmp_path):
    s = load_study(_write(fake, BASE + 'sweep = { levels = [2, 4] }\n'
                          '[[paths]]\npreset = "slowpan"\n'))
    s2 = s.with_overrides(frames=2, resolution="12x11")
    assert s2.resolution == (12, 11) and s2.paths[0].frames == 2
    back = tmp_path / "resolved.toml"
    back.write_text(to_toml(s2))
    s3 = load_study(back)
    assert (s3.resolution, s3.paths, s3.variants, s3.reference, s3.metrics) == (
        s2.resolution, s2.paths, s2.variants, s2.reference, s2.metrics)


@pytest.mark.parametrize("text", ["64x48", [64, 48], "64X48"])
def test_resolution_forms(text):
    assert parse_resolution(text) == (64, 48)


# (what is wrong, the study text, the key path, words the message must contain)
MALFORMED = [
    ("invalid TOML", "name = \n", "", "invalid TOML"),
    ("unknown top key", BASE + "\n", None, None),  # placeholder replaced below
    ("unknown top-level key", "colour = 1\n" + BASE, "colour", "unknown key"),
    ("scenes missing", 'name = "t"\n[[pipelines]]\ntype = "flat"\n', "(top level)",
     "missing required key 'scenes'"),
    ("resolution zero", BASE.replace('"24x16"', '"0x16"'), "resolution", "got 0x16"),
    ("resolution garbage", BASE.replace('"24x16"', '"big"'), "resolution", "'big'"),
    ("resolution too large", BASE.replace('"24x16"', "[100000, 10]"), "resolution", "1..8192"),
    ("frames not int", 'frames = "three"\n' + BASE, "frames", "expected an integer"),
    ("frames zero", "frames = 0\n" + BASE, "frames", ">= 1"),
    ("unknown metric", 'metrics = ["psnr", "vmaf"]\n' + BASE, "metrics[1]", "'vmaf'"),
    ("unknown figure", 'figures = ["nope"]\n' + BASE, "figures[0]", "unknown name"),
    ("empty scenes", BASE.replace('["tiny"]', "[]"), "scenes", "non-empty list"),
    ("unknown scene", BASE.replace('["tiny"]', '["castle"]'), "scenes[0].name",
     "unknown scene 'castle'"),
    ("missing scene file", BASE.replace('["tiny"]', '["configs/scenes/nope.toml"]'),
     "scenes[0].name", "not found"),
    ("scene is a number", BASE.replace('["tiny"]', "[3]"), "scenes[0]", "expected a table"),
    ("duplicate scene", BASE.replace('["tiny"]', '["tiny", "tiny"]'), "scenes[1].label",
     "used twice"),
    ("unknown pipeline", BASE.replace('"flat"', '"dacs_xl"'), "pipelines[0].type",
     "'dacs_xl' is not registered; registered:"),
    ("pipelines missing type", BASE.replace('type = "flat"', 'label = "x"'), "pipelines[0]",
     "missing required key 'type'"),
    ("unknown pipeline key", BASE + "colour = 3\n", "pipelines[0].colour", "unknown key"),
    ("unknown param", BASE + "params = { treshold = 0.1 }\n", "pipelines[0].params.treshold",
     "has no parameter 'treshold'"),
    ("wrong param type", BASE + 'params = { noise = "lots" }\n', "pipelines[0].params.noise",
     "expected a finite number"),
    ("bool for int", BASE + "params = { levels = true }\n", "pipelines[0].params.levels",
     "expected an integer"),
    ("width in params", BASE + "params = { width = 10 }\n", "pipelines[0].params.width",
     "resolution is set for the whole study"),
    ("rejected by the config", BASE + "params = { levels = 0 }\n", "pipelines[0].params",
     "levels must be >= 1"),
    ("empty sweep", BASE + "sweep = { levels = [] }\n", "pipelines[0].sweep.levels",
     "non-empty list"),
    ("sweep not a list", BASE + "sweep = { levels = 4 }\n", "pipelines[0].sweep.levels",
     "non-empty list"),
    ("sweep wrong element type", BASE + 'sweep = { noise = [0.1, "x"] }\n',
     "pipelines[0].sweep.noise", "expected a finite number"),
    ("zip unequal", BASE + 'sweep = { levels = [1, 2], noise = [0.1] }\nsweep_mode = "zip"\n',
     "pipelines[0].sweep", "equal length"),
    ("bad sweep mode", BASE + 'sweep_mode = "diagonal"\n', "pipelines[0].sweep_mode",
     "'cartesian' or 'zip'"),
    ("param fixed and swept", BASE + "params = { levels = 2 }\nsweep = { levels = [4] }\n",
     "pipelines[0].sweep.levels", "both a fixed parameter and swept"),
    ("duplicate label", BASE + '[[pipelines]]\ntype = "flat"\n', "pipelines[1].label",
     "used twice"),
    ("unknown pipeline preset", BASE + 'preset = "turbo"\n', "pipelines[0].preset",
     "no pipeline preset 'turbo'"),
    ("unknown path preset", BASE + '[[paths]]\npreset = "zoom"\n', "paths[0].preset",
     "no camera path preset 'zoom'"),
    ("unknown path type", BASE + '[[paths]]\ntype = "spiral"\n', "paths[0].type",
     "unknown camera path type 'spiral'"),
    ("orbit distance with center", BASE + '[[paths]]\ntype = "orbit"\nparams = { '
     'degrees_per_frame = 1.0, distance = 2.0, center = [0, 0, 0] }\n',
     "paths[0].params.distance", "'distance' has no effect when 'center' is given"),
    ("path frames negative", BASE + '[[paths]]\ntype = "static"\nframes = -2\n',
     "paths[0].frames", ">= 1"),
    ("unknown reference key", BASE + "[reference]\nk = 8\n", "reference.k", "unknown key"),
    ("reference param type", BASE + '[reference]\nparams = { samples = 2.5 }\n',
     "reference.params.samples", "expected an integer"),
    ("timing repeats zero", BASE + "[timing]\nrepeats = 0\n", "timing.repeats", ">= 1"),
    ("timing outputs unknown", BASE + '[timing]\noutputs = "counts"\n', "timing.outputs",
     "expected one of 'images', 'all', got 'counts'"),
    ("too small for MSSIM", BASE.replace('"24x16"', '"24x8"'), "resolution",
     "MSSIM needs images of at least 11x11"),
    ("save_frames negative", "save_frames = [-1]\n" + BASE, "save_frames[0]", ">= 0"),
]
MALFORMED = [m for m in MALFORMED if m[2] is not None]


@pytest.mark.parametrize("what,text,key,words", MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed(fake, what, text, key, words):
    p = _write(fake, text)
    with pytest.raises(StudyError) as e:
        load_study(p)
    msg = str(e.value)
    assert msg.startswith(f"{p}: "), msg
    assert e.value.path == key, msg
    assert words in msg, msg
    assert "\n" not in msg


def test_malformed_preset_names_the_preset_file(fake):
    (fake / "configs" / "pipelines" / "broken.toml").write_text('type = "flat"\nspeed = 1\n')
    with pytest.raises(StudyError, match=r"configs/pipelines/broken.toml: speed: unknown key"):
        load_study(_write(fake, BASE + 'preset = "broken"\n'))


def test_missing_file(fake):
    with pytest.raises(StudyError, match="nope.toml: no such file"):
        load_study(fake / "nope.toml")


def test_bad_override(fake):
    s = load_study(_write(fake, BASE))
    with pytest.raises(UserError, match="--resolution"):
        s.with_overrides(resolution="10")
    with pytest.raises(UserError, match="MSSIM needs"):
        s.with_overrides(resolution="10x10")


def test_builtin_presets_are_found_with_no_local_configs(tmp_path):
    # A study outside any checkout: pan_slow and dacs_threshold_sweep come from the package.
    p = tmp_path / "own.toml"
    p.write_text(textwrap.dedent("""
        resolution = "24x16"
        scenes = ["courtyard"]
        paths = [{ preset = "pan_slow", frames = 2 }]
        [[pipelines]]
        preset = "dacs_threshold_sweep"
        """))
    s = load_study(p)
    assert (s.paths[0].type, s.paths[0].frames) == ("pan", 2)
    assert len(s.variants) == 5 and {v.type for v in s.variants} == {"dacs"}
    assert s.scenes[0].source.endswith("configs/scenes/courtyard.toml"), s.scenes[0].source
    text = to_toml(s)
    assert "# preset 'pan_slow': built-in (" in text, text
    assert "# preset 'dacs_threshold_sweep': built-in (" in text, text


def test_local_preset_overrides_builtin_and_is_recorded(tmp_path):
    (tmp_path / "configs" / "paths").mkdir(parents=True)
    local = tmp_path / "configs" / "paths" / "pan_slow.toml"
    local.write_text('type = "pan"\nframes = 3\n[params]\npixels_per_frame = 2.0\n')
    p = tmp_path / "own.toml"
    p.write_text('resolution = "24x16"\nscenes = ["spheres"]\npaths = ["pan_slow"]\n'
                 '[[pipelines]]\ntype = "deferred"\n')
    s = load_study(p)
    assert dict(s.paths[0].params) == {"pixels_per_frame": 2.0}, s.paths[0]
    assert (f"# preset 'pan_slow': {tmp_path / 'configs'} ({local}, overrides the built-in)"
            in to_toml(s)), to_toml(s)
    # --configs names another folder, which replaces the one beside the study
    other = tmp_path / "elsewhere"
    (other / "paths").mkdir(parents=True)
    assert dict(load_study(p, configs=other).paths[0].params) == {"pixels_per_frame": 0.5}
    with pytest.raises(UserError, match="--configs: configs folder .*nope not found"):
        load_study(p, configs=tmp_path / "nope")


def test_unknown_preset_lists_builtin_and_local(fake):
    with pytest.raises(StudyError) as e:
        load_study(_write(fake, BASE + '[[paths]]\npreset = "zoom"\n'))
    msg = str(e.value)
    assert "pan_slow" in msg and "slowpan (local)" in msg, msg


def test_bundled_study_by_name():
    s = load_study("quickstart")
    assert s.name == "quickstart" and s.file.endswith("studies/quickstart.toml"), s.file
    with pytest.raises(UserError, match="bundled studies: .*quickstart"):
        load_study("no_such_study")


def test_check_convergence_turns_on_the_reference_convergence_render(tmp_path):
    base = ('resolution = "24x16"\nscenes = ["spheres"]\n[[pipelines]]\ntype = "deferred"\n'
            '[reference]\npipeline = "reference"\n')
    p = tmp_path / "s.toml"
    p.write_text(base)
    assert "convergence" not in dict(load_study(p).reference.params)
    p.write_text(base + "check_convergence = true\n")
    assert dict(load_study(p).reference.params)["convergence"] is True
    p.write_text(base + "check_convergence = true\nparams = { convergence = false }\n")
    with pytest.raises(StudyError, match="reference.params.convergence: check_convergence"):
        load_study(p)
    p.write_text(base.replace('"reference"\n', '"deferred"\n') + "check_convergence = true\n")
    with pytest.raises(StudyError, match="reference.check_convergence: .* no 'convergence'"):
        load_study(p)
