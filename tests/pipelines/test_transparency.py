"""Transparency: blended quads against the hand-computed over composite in every pipeline and
submission order, the layer cap's further passes and its named error, weighted blended OIT
against its analytic formula, an opaque scene compiling no transparent pass, and the pass
leaving a frame as its output-neutral settings promise.

The quads are lit by ambient light of 1 alone, so a surface's radiance is its albedo; the
middle of the screen is covered by every quad. One scene shape per layer count, so each
pipeline compiles once for all the submission orders."""

from __future__ import annotations

import itertools

import jax
import numpy as np
import pytest

from jaxrender.pipelines import PipelineOverflow, get_pipeline, make_config
from jaxrender.pipelines.dispatch import ENV_LAUNCH
from tests.pipelines.transparent_scenes import BACKGROUND, BLUE, THREE, TWO, layered_quads, over

W, H = 32, 18
MIDDLE = (slice(7, 11), slice(13, 19))  # pixels inside every quad
TOL = 2e-6  # float32 rounding of a few blends
SORTED_PIPELINES = ["forward", "deferred", "visbuffer", "dacs", "checkerboard", "reference"]


def _render(scene, pipeline, **params):
    if pipeline == "reference":
        params.setdefault("k", 1)
    cfg = make_config(pipeline, width=W, height=H, **params)
    return get_pipeline(pipeline).render(scene, scene.camera, cfg)


def _back_to_front(layers):
    return [(c, a, b) for c, a, b, _ in sorted(layers, key=lambda lay: lay[3])]


def _check_middle(image, expected, err_msg):
    got = np.asarray(image)[MIDDLE].reshape(-1, 3)
    np.testing.assert_allclose(got, np.broadcast_to(expected, got.shape), atol=TOL, rtol=0,
                               err_msg=err_msg)


@pytest.mark.parametrize("pipeline, layer_sets", [
    ("forward", (THREE,)), ("deferred", (THREE,)), ("tads", (THREE,)),
    # Two layers put fewer fragments in front than the screen has pixels, three more: object
    # space's two lengths of its transparent sample list.
    ("object_space", (TWO, THREE)),
    pytest.param("forward", (TWO,), marks=pytest.mark.slow),
    pytest.param("deferred", (TWO,), marks=pytest.mark.slow),
    pytest.param("reference", (TWO, THREE), marks=pytest.mark.slow)])
def test_sorted_modes_match_the_over_composite_in_every_order(pipeline, layer_sets):
    for layers in layer_sets:
        expected = over(_back_to_front(layers), BACKGROUND)
        for order in itertools.permutations(range(len(layers))):
            f = _render(layered_quads(layers, order), pipeline)
            _check_middle(f.image, expected, f"{pipeline}, submission order {order}")
            assert int(f.counts["transparent_layers_max"]) == len(layers)


@pytest.mark.slow
@pytest.mark.parametrize("pipeline", ["visbuffer", "dacs", "checkerboard"])
def test_sorted_modes_of_the_other_pipelines(pipeline):
    expected = over(_back_to_front(THREE), BACKGROUND)
    for order in itertools.permutations(range(3)):
        _check_middle(_render(layered_quads(THREE, order), pipeline).image, expected,
                      f"{pipeline}, submission order {order}")


@pytest.mark.parametrize("layer_sets", [(THREE,), pytest.param((TWO,), marks=pytest.mark.slow)])
def test_unsorted_forward_blends_in_submission_order(layer_sets):
    """sort_transparent = false: the layers blend in draw order, the first drawn as the
    farthest; it equals the sorted composite only where the order was back to front."""
    for layers in layer_sets:
        truth = over(_back_to_front(layers), BACKGROUND)
        for order in itertools.permutations(range(len(layers))):
            drawn = [layers[i][:3] for i in order]
            predicted = over(drawn, BACKGROUND)
            f = _render(layered_quads(layers, order), "forward", sort_transparent=False)
            _check_middle(f.image, predicted, f"unsorted forward, order {order}")
            back_to_front = [layers[i][3] for i in order] == sorted(lay[3] for lay in layers)
            differs = np.abs(predicted - truth).max() > 1e-3
            assert differs == (not back_to_front), (order, predicted, truth)


def test_layer_cap_runs_further_passes_or_names_the_cap():
    scene = layered_quads(THREE)
    deep = _render(scene, "deferred", transparent_layers=8)
    for cap in (2,):
        f = _render(scene, "deferred", transparent_layers=cap)
        np.testing.assert_allclose(np.asarray(f.image), np.asarray(deep.image), atol=TOL, rtol=0,
                                   err_msg=f"transparent_layers={cap} (chunks)")
        assert int(f.counts["transparent_passes"]) == -(-3 // cap)
    with pytest.raises(PipelineOverflow, match="transparent_layers=2"):
        _render(scene, "deferred", transparent_layers=2, transparent_overflow="error")


@pytest.mark.parametrize("pipeline", ["deferred", pytest.param("forward", marks=pytest.mark.slow)])
def test_weighted_oit_differs_from_the_sort_by_the_analytic_amount(pipeline):
    """McGuire and Bavoil (2013) eq. 7 on two over layers at view depths 2.5 and 3 (camera at
    z = 3 looking down -z): sum(w a c) / sum(w a) (1 - prod(1 - a)) + prod(1 - a) c0. A third
    quad of opacity 0 adds nothing to either (and shares the three-quad programs)."""
    scene = layered_quads(TWO + [(BLUE, 0.0, "over", -0.4)])
    (c1, a1, _, z1), (c2, a2, _, z2) = TWO
    d = lambda z: np.clip(10 / (1e-5 + (z / 5) ** 2 + (z / 200) ** 6), 1e-2, 3e3)  # noqa: E731
    w1, w2 = a1 * d(3.0 - z1), a2 * d(3.0 - z2)
    c1, c2, c0 = np.asarray(c1), np.asarray(c2), np.asarray(BACKGROUND)
    reveal = (1 - a1) * (1 - a2)
    wb = (w1 * a1 * c1 + w2 * a2 * c2) / (w1 * a1 + w2 * a2) * (1 - reveal) + reveal * c0
    exact = over(_back_to_front(TWO), BACKGROUND)
    sorted_img = np.asarray(_render(scene, pipeline).image)
    weighted = np.asarray(_render(scene, pipeline, oit="weighted").image)
    _check_middle(sorted_img, exact, f"{pipeline}: sorted")
    diff = (weighted - sorted_img)[MIDDLE].reshape(-1, 3)
    np.testing.assert_allclose(diff, np.broadcast_to(wb - exact, diff.shape), atol=1e-5,
                               rtol=0, err_msg=f"{pipeline}: WBOIT - sorted")
    assert np.abs(wb - exact).max() > 0.01  # the approximation's error is visible


def _lowered_text(scene, pipeline, **params):
    cfg = make_config(pipeline, width=16, height=8, **params)
    pipe = get_pipeline(pipeline)

    def fn(sc, cam):
        return pipe.step(sc, None, pipe.init(sc, None, cam, cfg), cam, 0, cfg)[0].image

    return jax.jit(fn).lower(scene, scene.camera).as_text(debug_info=True)


@pytest.mark.parametrize("pipeline", ["forward", "deferred", "reference"])
def test_an_opaque_scene_compiles_no_transparent_pass(pipeline):
    opaque = layered_quads([], name="opaque")
    blended = layered_quads(TWO)
    assert not opaque.effects.transparency and blended.effects.transparency
    # The pass's named scope in the program's locations (the op names).
    assert "transparent/" not in _lowered_text(opaque, pipeline), pipeline
    assert "transparent/" in _lowered_text(blended, pipeline), pipeline


def test_blending_settings_are_refused_without_transparency():
    opaque = layered_quads([], name="opaque")
    for pipeline, params in [("deferred", {"oit": "weighted"}),
                             ("forward", {"sort_transparent": False}),
                             ("visbuffer", {"transparent_layers": 2}),
                             ("tads", {"transparent_overflow": "error"}),
                             ("object_space", {"oit": "weighted"})]:
        key = next(iter(params))
        with pytest.raises(ValueError, match=f"{key} has no effect"):
            _render(opaque, pipeline, **params)
    with pytest.raises(ValueError, match="transparent_layers has no effect"):
        make_config("deferred", oit="weighted", transparent_layers=2)
    with pytest.raises(ValueError, match="sort_transparent = false has no effect"):
        make_config("forward", oit="weighted", sort_transparent=False)


@pytest.mark.parametrize("pipeline", ["deferred", "forward"])
def test_the_pass_leaves_a_frame_as_its_neutral_settings_promise(monkeypatch, pipeline):
    """The auto chunk takes the one-launch pass, a chunk given (or a launch mode named) the
    chunked one, and a longer fragment list other prefix lengths: ``chunk`` and
    ``fragment_capacity`` are OUTPUT_NEUTRAL, so the image bit for bit and every count stay as
    they are. (Checkerboard, DACS and the visibility buffer call the pass as deferred does;
    forward calls it after its opaque draw.)"""
    monkeypatch.delenv(ENV_LAUNCH, raising=False)
    scene = layered_quads(THREE)
    assert {"chunk", "fragment_capacity"} <= set(make_config(pipeline).OUTPUT_NEUTRAL)
    frames = {name: _render(scene, pipeline, **params)  # the first as the tests above
              for name, params in [("one launch", {}), ("chunks of 64", {"chunk": 64}),
                                   ("a longer list", {"fragment_capacity": 16 * W * H})]}
    want = frames["one launch"]
    assert int(want.counts["transparent_invocations"]) > 0
    for name, got in frames.items():
        np.testing.assert_array_equal(np.asarray(got.image), np.asarray(want.image),
                                      err_msg=f"{name} against the one launch")
        assert set(got.counts) == set(want.counts), name
        for key, value in want.counts.items():
            np.testing.assert_array_equal(np.asarray(got.counts[key]), np.asarray(value),
                                          err_msg=f"{name}: {key}")


def test_forward_runs_the_layer_shader_on_its_transparent_units_alone():
    # Forward shades its opaque units with the three-channel shader; the layer shader (colour,
    # opacity, depth) runs in the transparent pass over the listed transparent units. Read off
    # the traced program: the dispatch loop of the opaque units writes a float32[F, 3] array
    # for the F entries of the draw list, and no loop writes five channels for as many.
    from jaxrender.pipelines.forward import frame
    from tests.jaxpr_walk import all_equations

    scene = layered_quads(THREE)
    cfg = make_config("forward", width=W, height=H)
    closed = jax.make_jaxpr(lambda: frame(scene, scene.camera, cfg))()
    rows = {3: [], 5: []}
    for eqn in all_equations(closed.jaxpr):
        if eqn.primitive.name != "while":
            continue
        for v in eqn.outvars:
            shape = v.aval.shape
            if len(shape) == 2 and shape[1] in rows and v.aval.dtype == np.float32:
                rows[shape[1]].append(shape[0])
    assert rows[3], "no dispatch loop writes the opaque units' colours"
    n_units = max(rows[3])
    assert all(n < n_units for n in rows[5]), (
        f"a loop writes layer values for {max(rows[5])} entries, the draw list's {n_units}")


def test_forward_lists_its_opaque_and_transparent_fragments_apart():
    # As engines draw them: the opaque triangles' fragments in forward's draw list, the
    # transparent ones in the transparent pass's own list, each of fragment_capacity
    # entries. A capacity of one fragment a pixel holds the background's fragments and the
    # two quads' (under 576 each), not all of them together.
    scene = layered_quads(TWO)
    whole = _render(scene, "forward")
    total = int(whole.counts["fragments"])
    assert total > W * H, f"the scene's {total} fragments fit one list of {W * H}"
    tight = _render(scene, "forward", fragment_capacity=W * H)
    assert int(tight.counts["overflow"]) == 0, "a list overflowed"
    assert int(tight.counts["fragments"]) == total, "fragments counted"
    np.testing.assert_array_equal(np.asarray(tight.image), np.asarray(whole.image),
                                  err_msg="forward with one fragment a pixel a list")
