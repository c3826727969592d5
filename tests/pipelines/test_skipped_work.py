"""Skipped work stays skipped, counted at run time: every evaluation of the shader's light
layer (``shading.shade``'s ``_light_terms``, the one place a layer is computed) reports from
inside the compiled program how many lanes it ran and how many of them were live. Checkerboard
shades half the points of deferred and runs half the layer evaluations, the counts the
pipelines report are those evaluations, and a shader cost of c runs each chunk's layer 1 + c
times: ``shading_work = shade_invocations x (1 + shader_cost)`` is the work the program did."""

from __future__ import annotations

import dataclasses
import importlib

import jax
import jax.numpy as jnp
import numpy as np

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines import make_config, program
from jaxrender.pipelines.registry import get_pipeline
from jaxrender.study import shader_cost
from tests.pipelines.dacs_scenes import H, W, shapes_scene

CHUNK = 64  # lanes per dispatch chunk: small, so a half-size list launches half the chunks
COST = 3


def _counted(monkeypatch):
    """Patch the layer evaluation to report (lanes, live points) per call; returns the list."""
    shade_module = importlib.import_module("jaxrender.shading.shade")
    calls: list = []
    layer = getattr(shade_module, "_light_terms")

    def counting(frame, scene, effects, normal, *args):
        # The normal is the one argument that differs between the shader-cost layers (batched
        # over them): passing one of its values makes the callback run once per layer.
        jax.debug.callback(lambda lanes, live, _: calls.append((int(lanes), int(live))),
                           frame.valid.shape[0], jnp.sum(frame.valid, dtype=jnp.int32),
                           normal[0][0])
        return layer(frame, scene, effects, normal, *args)

    monkeypatch.setattr(shade_module, "_light_terms", counting)
    return calls


def _render(pipeline: str, scene, calls: list):
    """One frame of ``pipeline`` and the layer evaluations it ran (fresh compile: the patched
    layer must be traced into the program)."""
    program.clear_cache()
    calls.clear()
    cfg = make_config(pipeline, width=W, height=H, chunk=CHUNK)
    frame = program.render(get_pipeline(pipeline), scene, scene.camera, cfg)
    jax.block_until_ready(frame.image)
    jax.effects_barrier()
    return frame, list(calls)


def test_half_the_points_half_the_layer_evaluations(monkeypatch):
    monkeypatch.delenv(dispatch.ENV_LAUNCH, raising=False)  # the default: exact lanes
    calls = _counted(monkeypatch)
    scene = shapes_scene()  # covers every pixel
    try:
        full, full_calls = _render("deferred", scene, calls)
        costly = dataclasses.replace(scene, effects=scene.effects.replace(shader_cost=COST))
        half, half_calls = _render("checkerboard", costly, calls)
    finally:
        program.clear_cache()
    inv_full = int(full.counts["shade_invocations"])
    inv_half = int(half.counts["shade_invocations"])
    assert inv_full == W * H and inv_half == W * H // 2, (inv_full, inv_half)
    # Deferred at cost 0: one layer evaluation per launch (of one chunk, or of a block of them
    # in the default launch mode), over whole chunks; the live lanes are its invocations.
    full_lanes = sum(lanes for lanes, _ in full_calls)
    assert all(lanes % CHUNK == 0 for lanes, _ in full_calls), full_calls
    assert full_lanes == -(-inv_full // CHUNK) * CHUNK, full_calls
    assert sum(live for _, live in full_calls) == inv_full
    # Checkerboard at cost 3: half the chunks, each launch running its layer 1 + 3 times.
    chunks_half = -(-inv_half // CHUNK)
    half_lanes = sum(lanes for lanes, _ in half_calls)
    assert half_lanes == chunks_half * CHUNK * (1 + COST), (half_lanes, chunks_half)
    live_evals = sum(live for _, live in half_calls)
    assert live_evals == shader_cost.shading_work(inv_half, COST), live_evals
    np.testing.assert_equal(2 * half_lanes // (1 + COST), full_lanes,
                            err_msg="checkerboard launches half deferred's lanes per layer")
