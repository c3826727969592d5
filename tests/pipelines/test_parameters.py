"""Nothing accepted and ignored: every config field of every built-in pipeline either changes
the output or is declared ``OUTPUT_NEUTRAL`` and leaves it unchanged (counts and aux arrays
bit-identical, the image within a few ulps of compiler rounding: ``NEUTRAL_IMAGE_ULPS``).

``CASES`` gives, per pipeline and field (every dataclass field but width and height), an input
on which changing that field alone changes the image, a count or an aux array: a scene, the
base parameters that make the field matter (``per_sample_shading`` needs MSAA, ``vrs_rate``
needs ``vrs = "fixed"``, ...), the changed value, and whether the frames are a camera path
(state carried). A test checks that the table covers exactly each registered built-in
pipeline's fields, so a new field without a case fails, naming it. ``NEUTRAL_VALUES`` gives a
changed value for every OUTPUT_NEUTRAL field.

A field that has no effect in some configuration of the *other* fields is refused there by its
config's ``__post_init__`` (``REFUSED``); a field whose effect depends on the scene (a MIP bias
step without a full store, xatlas settings for meshes with their own unique UVs) is not.

Cost: every distinct config is one compiled program, and the rasterizer in each alone is
seconds of XLA on a CPU. So the frames are tiny, one small scene serves almost every case, the
stateful pipelines run every case as one 3-frame pan (one base program), and each outcome is
rendered once and shared between the cases that need it (a contextual base is often another
case's changed config). That is still about 70 programs, about 15 minutes on one core, so the
renders are marked ``slow`` (``pytest -m slow``); the table's completeness and the refusals,
which need no render, run by default.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, NamedTuple

import numpy as np
import pytest

from jaxrender.pipelines import (PipelineOverflow, RenderConfig, get_pipeline, list_pipelines,
                                 make_config)
from jaxrender.pipelines import program
from jaxrender.scene.camera_path import pan
from jaxrender.shading import load_lit_scene

W, H = 24, 16
FRAMES = 3  # a pan of this many frames for the stateful pipelines (history, store)
PAN_PIXELS = 2.0  # per frame
# An image change at float32 rounding level is not an effect of a field (the same shading
# compiled into a different program can differ by an ulp or two: ~1e-7 here); counts and aux
# arrays must differ exactly.
IMAGE_NOISE = 1e-6

# Leaf cards: alpha-tested (the fragment lists and the alpha-test dispatch run, so chunk and
# fragment_capacity are exercised), textured (LOD settings act), back faces in view (culling
# acts), several objects and two triangles per card (id kinds act), overdraw (Z pre-pass acts).
# Its cards are flat-lit and minified to near-constant colours, so DACS's luma variance never
# decides there: the luma settings take the smoothly lit spheres. Its charts (a card's own
# uvs) leave no shadel outside its owner triangle, so object_space's eps takes the slivers.
SCENES = {
    "foliage": ("foliage", {"n_cards": 40, "card_size": 1.2}),
    "spheres": ("spheres", {"rows": 1, "cols": 2, "lat": 6, "lon": 12}),
    "sliver": ("sliver", {"n_slivers": 16, "n_degenerate": 4}),
    # Panes and particles: pixels of several transparent layers (the blending settings act).
    "glass": ("glass", {"n_panes": 4, "n_particles": 8}),
}


class Case(NamedTuple):
    """Render ``scene`` with ``base`` and with ``base`` plus {field: changed}."""

    scene: str
    base: dict
    changed: Any
    sequence: bool = False


F, S, SL, G = "foliage", "spheres", "sliver", "glass"
SEQ = {"sequence": True}



def _blending(**extra) -> dict[str, Case]:
    """The transparent pass's settings (``BlendingConfig``), on the glass scene: a cap of one
    layer runs more passes (counts), or refuses the frame with "error"."""
    return {"oit": Case(G, {}, "weighted", **extra),
            "transparent_layers": Case(G, {}, 1, **extra),
            "transparent_overflow": Case(G, {"transparent_layers": 1}, "error", **extra)}


# DACS on the spheres: a threshold at which the luma weights and the variance space both move
# decisions (the threshold is traced: any value shares one program).
LUMA_THRESHOLD = 1.7e-5
# object_space: 18 chunks of 64 shadels, fewer than the ~20 the pan marks at bias 0 (the MIP
# bias is raised until they fit) and more than its coarsest levels need (16 overflow).
SMALL_STORE = 18 * 64
# With bias_feedback the pan's first frame is over that store (20 chunks: the bias is raised for
# the next frame, by 2 here) and the next just under it (17: with bias_low = 1 the bias relaxes
# by bias_relax).
FEEDBACK = {"store_shadels": SMALL_STORE, "bias_feedback": True, "bias_step": 2.0,
            "bias_low": 1.0}

CASES: dict[str, dict[str, Case]] = {
    "reference": {
        "k": Case(F, {}, 2),
        "chunk": Case(F, {}, 64),  # counts lanes, chunks, helper_lanes
        "convergence": Case(F, {}, True),  # adds counts["convergence_psnr"]
        "samples_per_pass": Case(F, {}, 1),  # counts lanes, chunks, work_items
    },
    "forward": {
        **_blending(),
        "sort_transparent": Case(G, {}, False),
        "cull_backfaces": Case(F, {}, True),
        "z_prepass": Case(F, {}, True),
        "msaa": Case(F, {}, 4),
        "shade_helpers": Case(F, {}, True),  # counts["shader_evaluations"]
        "wave_size": Case(F, {}, 64),
    },
    "deferred": {
        **_blending(),
        "cull_backfaces": Case(F, {}, True),
        "msaa": Case(F, {}, 4),
        "per_sample_shading": Case(F, {"msaa": 4}, True),
        "wave_size": Case(F, {}, 64),
    },
    "visbuffer": {
        **_blending(),
        "cull_backfaces": Case(F, {}, True),
        # The batch / primitive split only moves where an id overflows: with both at 0 bits the
        # second triangle of a card does not fit (the frame is refused, PipelineOverflow).
        "id_layout": Case(F, {}, "fixed"),  # the packed ids (aux) move
        "batch_bits": Case(F, {"id_layout": "fixed", "primitive_bits": 0}, 0),
        "primitive_bits": Case(F, {"id_layout": "fixed", "batch_bits": 0}, 0),
        "instance_bits": Case(F, {"id_layout": "fixed"}, 8),  # the packed ids (aux) move
        "wave_size": Case(F, {}, 64),
        "tiling": Case(F, {}, "tiles"),  # waves, unfilled lanes and command bytes move
        "vertex_fetch": Case(F, {}, "pixel"),  # counts["vertex_invocations"]
        "vrs": Case(F, {}, "fixed"),
        "vrs_rate": Case(F, {"vrs": "fixed"}, "1x2"),
        "vrs_thresholds": Case(F, {"vrs": "distance"}, (3.0, 5.0)),
        "rate_image": Case(F, {"vrs": "image", "rate_image": (("1x1",),)},
                           (("2x2", "1x1"), ("1x2", "2x1"))),
    },
    "dacs": {
        **_blending(),
        "cull_backfaces": Case(F, {}, True),
        "threshold": Case(F, {}, 0.0),
        "spacing": Case(F, {}, 8),
        "ids": Case(F, {}, "triangle"),
        "luma": Case(S, {"threshold": LUMA_THRESHOLD}, "rec709"),
        "variance_space": Case(S, {"threshold": LUMA_THRESHOLD}, "linear"),
        "warp_width": Case(F, {}, 64),
        "warp_batches": Case(F, {}, 1),
        "border": Case(F, {}, "shade"),  # 24x16: the last row and column lack a pair
        "chunk": Case(F, {}, 64),  # counts["dispatch_lanes"]
    },
    "checkerboard": {
        **_blending(**SEQ),
        "cull_backfaces": Case(F, {}, True, **SEQ),
        "pattern": Case(F, {}, "2x1", **SEQ),
        "frame": Case(F, {}, 1, **SEQ),
        "temporal": Case(F, {}, False, **SEQ),
        "ids": Case(F, {}, "none", **SEQ),
        "lod_bias": Case(F, {}, -1.0, **SEQ),
        "depth_tolerance": Case(F, {}, 1e-5, **SEQ),
        "wave_size": Case(F, {}, 64, **SEQ),
    },
    "object_space": {
        **_blending(**SEQ),
        "cull_backfaces": Case(F, {}, True, **SEQ),
        "store_shadels": Case(F, {}, SMALL_STORE, **SEQ),
        "store_per_pixel": Case(F, {}, SMALL_STORE / (W * H), **SEQ),  # the same store
        "mip_bias": Case(F, {}, 1.0, **SEQ),
        # A store too small for the marked chunks: the bias is raised in these steps.
        "bias_step": Case(F, {"store_shadels": SMALL_STORE}, 1.0, **SEQ),
        "filter": Case(F, {}, "bilinear", **SEQ),
        "aniso_taps": Case(F, {}, 4, **SEQ),
        # Shadels far outside their owner triangle: those a sliver conservatively owns.
        "eps": Case(SL, {}, 0.0, **SEQ),
        "sheet_resolution": Case(F, {}, 16, **SEQ),
        "texel_density": Case(F, {}, 16.0, **SEQ),  # the ground (untextured) is sized by it
        "max_sheet_resolution": Case(F, {}, 16, **SEQ),
        # Charts of meshes with unique own UVs come from xatlas only when forced.
        "xatlas_resolution": Case(F, {"force_xatlas": True}, 64, **SEQ),
        "force_xatlas": Case(F, {}, True, **SEQ),
        # The eye of a pan stays put and the leaves have no specular lobe, so with reuse
        # every shading frame copies its resident chunks anyway.
        "shade_every": Case(F, {"reuse": False}, 2, **SEQ),
        "reuse": Case(F, {}, False, **SEQ),
        "wave_size": Case(F, {}, 64, **SEQ),
        # Chunks left unshaded and a bias raised across frames, not retried within one.
        "bias_feedback": Case(F, {"store_shadels": SMALL_STORE}, True, **SEQ),
        "bias_low": Case(F, FEEDBACK, 0.05, **SEQ),  # under 1 chunk: the bias holds
        "bias_relax": Case(F, FEEDBACK, 0.25, **SEQ),
    },
    "tads": {
        **_blending(**SEQ),
        "cull_backfaces": Case(F, {}, True, **SEQ),
        "aniso_taps": Case(F, {}, 4, **SEQ),
        "shade_every": Case(F, {}, 2, **SEQ),
        # Taps of two ages in one pixel: the pan's in-between frames.
        "staleness": Case(F, {"shade_every": 2}, 0.0, **SEQ),
        "sheet_resolution": Case(F, {}, 16, **SEQ),
        "texel_density": Case(F, {}, 16.0, **SEQ),  # the ground (untextured) is sized by it
        "wave_size": Case(F, {}, 64, **SEQ),
    },
}

# A changed value for every OUTPUT_NEUTRAL field (chunks of 64 lanes: several per work list).
NEUTRAL_VALUES = {"chunk": 64, "fragment_capacity": 8 * W * H}
# The input of each pipeline's neutrality check: its cases' scene, and a path if stateful.
NEUTRAL_INPUT = {p: (F, get_pipeline(p).stateful) for p in CASES}
# The one allowance in bit-identity: the same shading compiled for another chunk width may
# round differently (XLA fuses it differently). Measured with chunk = 64: forward and
# object_space differ by 1 to 2 ulps in a few percent of the pixels (at XLA's -O0 and default
# level alike); deferred, visbuffer, checkerboard and DACS stay bit-identical. Counts and aux
# arrays must be bit-identical.
NEUTRAL_IMAGE_ULPS = 4

# (pipeline, params, field): a field set where the other fields leave it nothing to do; its
# config must refuse it, naming it.
REFUSED = [
    ("deferred", {"oit": "weighted", "transparent_layers": 2}, "transparent_layers"),
    ("forward", {"oit": "weighted", "sort_transparent": False}, "sort_transparent"),
    ("deferred", {"per_sample_shading": True}, "per_sample_shading"),
    ("visbuffer", {"vrs_rate": "1x2"}, "vrs_rate"),
    ("visbuffer", {"batch_bits": 8}, "batch_bits"),
    ("visbuffer", {"id_layout": "micro_batch", "instance_bits": 8}, "instance_bits"),
    ("visbuffer", {"vrs": "distance", "vrs_rate": "1x1"}, "vrs_rate"),
    ("visbuffer", {"vrs_thresholds": (1.0, 2.0)}, "vrs_thresholds"),
    ("visbuffer", {"vrs": "fixed", "vrs_thresholds": (1.0, 2.0)}, "vrs_thresholds"),
    ("visbuffer", {"rate_image": (("2x2",),)}, "rate_image"),
    ("visbuffer", {"vrs": "speed", "rate_image": (("2x2",),)}, "rate_image"),
    ("dacs", {"width": 33, "height": 21, "border": "shade"}, "border"),
    ("dacs", {"width": 33, "height": 17, "spacing": 8, "border": "shade"}, "border"),
    ("checkerboard", {"temporal": False, "depth_tolerance": 0.05}, "depth_tolerance"),
    ("object_space", {"sheet_resolution": 64, "texel_density": 32.0}, "texel_density"),
    ("object_space", {"sheet_resolution": 64, "max_sheet_resolution": 1024},
     "max_sheet_resolution"),
    ("object_space", {"sheet_resolution": 8192}, "sheet_resolution"),
    ("object_space", {"bias_low": 0.5}, "bias_low"),
    ("object_space", {"store_per_pixel": 2.0, "store_shadels": 4096}, "store_shadels"),
    ("object_space", {"bias_relax": 0.125}, "bias_relax"),
    ("tads", {"staleness": 0.5}, "staleness"),
    ("tads", {"sheet_resolution": 64, "texel_density": 32.0}, "texel_density"),
]

# Their neighbours that must stay valid: the same settings where they act, and the defaults
# given explicitly where they do not.
ACCEPTED = [
    ("deferred", {"per_sample_shading": True, "msaa": 2}),
    ("deferred", {"per_sample_shading": False, "msaa": 1}),
    ("visbuffer", {"vrs": "fixed", "vrs_rate": "1x2"}),
    ("visbuffer", {"id_layout": "fixed", "batch_bits": 8, "instance_bits": 8}),
    ("visbuffer", {"vrs": "off", "vrs_rate": "2x2", "vrs_thresholds": (8, 20), "rate_image": ()}),
    ("visbuffer", {"vrs": "speed", "vrs_thresholds": (1.0, 2.0)}),
    ("visbuffer", {"vrs": "motion", "vrs_thresholds": (1.0, 2.0)}),
    ("visbuffer", {"vrs": "image", "rate_image": (("2x2",),)}),
    ("dacs", {"width": 32, "height": 21, "border": "shade"}),
    ("dacs", {"width": 33, "height": 21, "border": "average"}),
    ("checkerboard", {"temporal": True, "depth_tolerance": 0.05}),
    ("checkerboard", {"temporal": False, "depth_tolerance": 0.01}),
    ("object_space", {"sheet_resolution": 0, "texel_density": 32.0, "max_sheet_resolution": 1024}),
    ("object_space", {"sheet_resolution": 64, "texel_density": 128.0}),
    ("object_space", {"sheet_resolution": 8192, "max_sheet_resolution": 8192}),
    ("object_space", {"bias_feedback": True, "bias_low": 0.5, "bias_relax": 0.125}),
    ("object_space", {"store_per_pixel": 2.0, "store_shadels": 0}),
    ("object_space", {"bias_feedback": False, "bias_low": 0.8, "bias_relax": 0.0625}),
    ("tads", {"shade_every": 2, "staleness": 0.5}),
    ("tads", {"sheet_resolution": 64, "texel_density": 128.0}),
]


# ---------------------------------------------------------------- rendering, cached


def _builtin_pipelines():
    """The pipelines registered by jaxrender's own modules (tests may register fakes)."""
    return {p.name: p for p in list_pipelines()
            if p.config_cls.__module__.startswith("jaxrender.pipelines.")}


# The temporal anti-aliasing settings every config inherits from RenderConfig are one
# implementation applied after any pipeline's resolve: their cases (each field changes the
# output; refused without ``taa``) are in tests/pipelines/test_taa.py, once.
TAA_FIELDS = {f.name for f in dataclasses.fields(RenderConfig) if f.name.startswith("taa")}


def _fields(pipe) -> set[str]:
    return ({f.name for f in dataclasses.fields(pipe.config_cls)} - {"width", "height"}
            - TAA_FIELDS)


@functools.lru_cache(maxsize=None)
def _scene(key: str):
    name, params = SCENES[key]
    return load_lit_scene(name, **params)


@functools.lru_cache(maxsize=None)
def _path(key: str):
    return pan(_scene(key).camera, FRAMES, PAN_PIXELS, H)


_current_pipeline = [None]


@functools.lru_cache(maxsize=None)
def _outcome(pipeline: str, scene: str, params: tuple, sequence: bool) -> dict:
    """{name: numpy array} of the image, every count and every aux array (a sequence: stacked
    over its frames), or {"raised": message} when the frame is refused for an overflow."""
    if _current_pipeline[0] != pipeline:
        # A compiled XLA:CPU program holds about a thousand memory maps until it is dropped,
        # and some 60 of them exceed Linux's vm.max_map_count (65530): the process then dies
        # inside a later compile. The cases run pipeline by pipeline and keep their outcomes,
        # so the programs of the previous pipeline are not needed again.
        program.clear_cache()
        _current_pipeline[0] = pipeline
    pipe = get_pipeline(pipeline)
    cfg = make_config(pipeline, width=W, height=H, **dict(params))
    sc = _scene(scene)
    try:
        frame = (pipe.render_sequence(sc, _path(scene), cfg) if sequence
                 else pipe.render(sc, sc.camera, cfg))
    except PipelineOverflow as e:
        return {"raised": np.asarray(str(e))}
    out = {"image": np.asarray(frame.image)}
    out.update({f"counts[{k!r}]": np.asarray(v) for k, v in (frame.counts or {}).items()})
    out.update({f"aux[{k!r}]": np.asarray(v) for k, v in (frame.aux or {}).items()})
    return out


def render(pipeline: str, scene: str, params: dict, sequence: bool) -> dict:
    return _outcome(pipeline, scene, tuple(sorted(params.items())), sequence)


def differences(a: dict, b: dict, image_noise: float = 0.0) -> list[str]:
    """The outputs that differ between two outcomes (an image only beyond ``image_noise``)."""
    diff = sorted(set(a) ^ set(b))
    for k in sorted(set(a) & set(b)):
        x, y = a[k], b[k]
        if x.shape != y.shape or x.dtype != y.dtype:
            diff.append(k)
        elif k == "image" and image_noise > 0.0:
            d = np.abs(x.astype(np.float64) - y.astype(np.float64))
            if np.any(np.isnan(x) != np.isnan(y)) or np.nanmax(d, initial=0.0) > image_noise:
                diff.append(k)
        elif not np.array_equal(x, y, equal_nan=x.dtype.kind == "f"):
            diff.append(k)
    return diff


# ---------------------------------------------------------------- the table is complete


def test_cases_cover_every_field_of_every_builtin_pipeline():
    pipes = _builtin_pipelines()
    assert sorted(CASES) == sorted(pipes), (
        f"CASES has pipelines {sorted(CASES)}, the registry {sorted(pipes)}: give every "
        f"registered pipeline a table of cases")
    for name, pipe in pipes.items():
        neutral = set(pipe.config_cls.OUTPUT_NEUTRAL)
        want = _fields(pipe) - neutral
        have = set(CASES[name])
        assert not have - want, (
            f"{name}: CASES has {sorted(have - want)}, not a field of its config or one "
            f"declared OUTPUT_NEUTRAL ({sorted(neutral)})")
        assert not want - have, (
            f"{name}: field(s) {sorted(want - have)} have no case in CASES: add an input on "
            f"which changing it changes the output, or declare it OUTPUT_NEUTRAL")
        missing = sorted(neutral - set(NEUTRAL_VALUES))
        assert not missing, f"{name}: OUTPUT_NEUTRAL field(s) {missing} have no NEUTRAL_VALUES"
        for field, case in CASES[name].items():
            defaults = {f.name: f.default for f in dataclasses.fields(pipe.config_cls)}
            assert case.changed != case.base.get(field, defaults[field]), (
                f"{name}.{field}: the changed value {case.changed!r} is the base value")


# ---------------------------------------------------------------- each field acts


FIELD_CASES = [(p, f) for p in CASES for f in CASES[p]]


@pytest.mark.slow
@pytest.mark.parametrize("pipeline,field", FIELD_CASES, ids=[f"{p}-{f}" for p, f in FIELD_CASES])
def test_field_changes_the_output(pipeline, field):
    case = CASES[pipeline][field]
    base = render(pipeline, case.scene, case.base, case.sequence)
    changed = render(pipeline, case.scene, {**case.base, field: case.changed}, case.sequence)
    diff = differences(base, changed, IMAGE_NOISE)
    assert diff, (
        f"{pipeline}.{field} = {case.changed!r} (base {case.base or 'defaults'}, scene "
        f"{case.scene}, {'a %d-frame pan' % FRAMES if case.sequence else 'one frame'}) changed "
        f"no output: {sorted(base)} are all identical (the image within {IMAGE_NOISE})")


NEUTRAL_CASES = [(p, f) for p in CASES
                 for f in get_pipeline(p).config_cls.OUTPUT_NEUTRAL]


@pytest.mark.slow
@pytest.mark.parametrize("pipeline,field", NEUTRAL_CASES,
                         ids=[f"{p}-{f}" for p, f in NEUTRAL_CASES])
def test_output_neutral_field_leaves_the_output_unchanged(pipeline, field):
    scene, sequence = NEUTRAL_INPUT[pipeline]
    base = render(pipeline, scene, {}, sequence)
    changed = render(pipeline, scene, {field: NEUTRAL_VALUES[field]}, sequence)
    assert "raised" not in base, f"{pipeline}: the neutrality input overflowed: {base['raised']}"
    assert sorted(base) == sorted(changed), (
        f"{pipeline}.{field} = {NEUTRAL_VALUES[field]!r} (OUTPUT_NEUTRAL) changed the outputs "
        f"present: {sorted(set(base) ^ set(changed))}")
    for k in base:
        msg = (f"{pipeline}.{field} = {NEUTRAL_VALUES[field]!r} is declared OUTPUT_NEUTRAL "
               f"but changed {k}")
        if k == "image":
            np.testing.assert_array_equal(np.isnan(changed[k]), np.isnan(base[k]), err_msg=msg)
            a, b = np.nan_to_num(changed[k]), np.nan_to_num(base[k])
            bound = NEUTRAL_IMAGE_ULPS * np.spacing(np.maximum(np.abs(a), np.abs(b)))
            np.testing.assert_array_less(np.abs(a - b), bound,
                                         err_msg=f"{msg} by more than {NEUTRAL_IMAGE_ULPS} ulps")
        else:
            np.testing.assert_array_equal(changed[k], base[k], err_msg=msg)


# ---------------------------------------------------------------- refused where it cannot act


@pytest.mark.parametrize("pipeline,params,field", REFUSED,
                         ids=[f"{p}-{f}-{i}" for i, (p, _, f) in enumerate(REFUSED)])
def test_field_without_effect_in_its_config_is_refused(pipeline, params, field):
    with pytest.raises(ValueError, match=field) as info:
        make_config(pipeline, **params)
    assert "no effect" in str(info.value) or "capped" in str(info.value), (
        f"{pipeline} {params}: the refusal of {field} does not say why: {info.value}")


@pytest.mark.parametrize("pipeline,params", ACCEPTED,
                         ids=[f"{p}-{i}" for i, (p, _) in enumerate(ACCEPTED)])
def test_neighbours_of_a_refusal_stay_valid(pipeline, params):
    cfg = make_config(pipeline, **params)
    for k, v in params.items():
        got = getattr(cfg, k)
        assert got == v or (isinstance(v, tuple) and tuple(got) == tuple(map(float, v))), (
            f"{pipeline}: {k} = {v!r} was accepted as {got!r}")


@pytest.mark.parametrize("width,height", [(320, 180), (33, 21), (33, 17), (1, 1)])
def test_default_configs_stay_valid(width, height):
    # A refusal compares with the field's default, so no default config is refused (at 33x21
    # and 33x17 DACS's border cannot act; the default border is still accepted).
    for name in _builtin_pipelines():
        make_config(name, width=width, height=height)
