"""The pipelines whose loops and branches XLA GPU keeps in CUDA graphs
(``program.DEVICE_CONTROL_FLOW``) compile with that option at the top level, and still render
inside another program's trace, where jax takes no compiler options: the same image each way."""

from __future__ import annotations

import jax
import numpy as np

from jaxrender.pipelines import make_config, program
from jaxrender.pipelines.registry import get_pipeline
from jaxrender.shading import load_lit_scene


def test_device_control_flow_is_a_compile_option_of_its_pipelines_alone():
    forward, deferred = get_pipeline("forward"), get_pipeline("deferred")
    assert "forward" in program.DEVICE_CONTROL_FLOW
    assert "deferred" not in program.DEVICE_CONTROL_FLOW
    assert program.program_jit(forward) is not program.program_jit(deferred)
    assert program.program_jit(deferred) is program.program_jit(get_pipeline("dacs"))


def test_a_pipeline_with_device_control_flow_renders_inside_another_program():
    scene = load_lit_scene("room")
    pipe, cfg = get_pipeline("forward"), make_config("forward", width=40, height=24)
    top = np.asarray(pipe.render(scene, scene.camera, cfg).image)
    closed_over = np.asarray(jax.jit(lambda: pipe.render(scene, scene.camera, cfg).image)())
    traced = np.asarray(jax.jit(lambda s: pipe.render(s, scene.camera, cfg).image)(scene))
    assert np.isfinite(top).all() and top.max() > 0.0, "the image is empty"
    np.testing.assert_array_equal(closed_over, top, err_msg="inside a jit, closed over")
    np.testing.assert_array_equal(traced, top, err_msg="inside a jit, traced")
