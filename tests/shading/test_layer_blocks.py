"""The shader-cost layers in blocks (``shade.layer_sum``): a launch whose layers x lanes exceed
``LAYER_LANES`` evaluates its layers in a loop of blocks, each layer exactly once, with the sum
of the single batch, and with temporaries bounded by the block rather than by every layer."""

from __future__ import annotations

import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.shading import load_lit_scene, shade
from jaxrender.shading.surface import surface_points
from jaxrender.study.backend import with_shader_cost

SHADE_MODULE = sys.modules[shade.__module__]


@pytest.mark.parametrize("n_layers, lanes, budget", [(7, 5, 10), (9, 4, 12), (6, 3, 100)])
def test_every_layer_is_evaluated_once_whatever_the_blocks(monkeypatch, n_layers, lanes, budget):
    # (7, 5, 10): blocks of 2, a loop of 3 and one layer after it; (9, 4, 12): blocks of 3,
    # no remainder; (6, 3, 100): one batch, no loop.
    monkeypatch.setattr(SHADE_MODULE, "LAYER_LANES", budget)
    rng = np.random.default_rng(7)
    angles = jnp.asarray(rng.uniform(-1, 1, n_layers), jnp.float32)
    weights = jnp.asarray(rng.uniform(0, 1, (lanes, 3)), jnp.float32)

    def layer(a):  # a count of evaluations beside a value
        return jnp.concatenate([jnp.sin(weights + a), jnp.ones((lanes, 1))], axis=1)

    got = jax.jit(lambda a: SHADE_MODULE.layer_sum(layer, a, lanes))(angles)
    want = np.sin(np.asarray(weights)[None] + np.asarray(angles)[:, None, None]).sum(axis=0)
    np.testing.assert_array_equal(np.asarray(got[:, 3]), n_layers,
                                  err_msg="every layer once, none padded")
    np.testing.assert_allclose(np.asarray(got[:, :3]), want, rtol=1e-6, atol=1e-6,
                               err_msg="the blocks' sum is the layers' sum")
    jaxpr = str(jax.make_jaxpr(lambda a: SHADE_MODULE.layer_sum(layer, a, lanes))(angles))
    looped = "while" in jaxpr or "scan" in jaxpr  # a fori_loop of static length is a scan
    assert looped == (n_layers * lanes > budget), jaxpr


def test_a_layer_of_several_values_is_summed_value_by_value(monkeypatch):
    # The shader's layers return one array a colour channel: blocks of 2, a loop of 3 and one
    # layer after it, as (7, 5, 10) above.
    monkeypatch.setattr(SHADE_MODULE, "LAYER_LANES", 10)
    rng = np.random.default_rng(8)
    angles = jnp.asarray(rng.uniform(-1, 1, 7), jnp.float32)
    weights = jnp.asarray(rng.uniform(0, 1, 5), jnp.float32)

    def layer(a):
        return jnp.sin(weights + a), jnp.cos(weights * a), jnp.ones((5,), jnp.int32)

    sines, cosines, count = jax.jit(lambda a: SHADE_MODULE.layer_sum(layer, a, 5))(angles)
    a, w = np.asarray(angles)[:, None], np.asarray(weights)[None]
    np.testing.assert_allclose(sines, np.sin(w + a).sum(axis=0), rtol=1e-6, atol=1e-6,
                               err_msg="the first value: its layers' sum")
    np.testing.assert_allclose(cosines, np.cos(w * a).sum(axis=0), rtol=1e-6, atol=1e-6,
                               err_msg="the second value: its layers' sum")
    np.testing.assert_array_equal(count, 7, err_msg="every layer once, in each value")


def _shade_program(scene, pts):
    return jax.jit(lambda s, p: shade(surface_points(s, s.camera, *p), s))


def test_a_costly_launch_shades_the_same_in_blocks_with_bounded_temporaries(monkeypatch):
    # 512 covered-or-not points of the foliage scene at shader cost 1023 (1024 layers): one
    # batch of 524,288 layer-lanes against blocks of 4 layers (2,048 layer-lanes). Foliage's
    # layers store about 4 bytes a layer-lane on a CPU, beside the shared terms the blocks
    # store too, so it takes this many layers for the batch's temporaries to dwarf those.
    scene = with_shader_cost(load_lit_scene("foliage"), 1023)
    rng = np.random.default_rng(11)
    n = 512
    tri = rng.integers(-1, scene.faces.shape[0], n).astype(np.int32)
    bary = rng.dirichlet(np.ones(3), n).astype(np.float32)
    zeros = np.zeros((n, 3), np.float32)
    pts = (jnp.asarray(tri), jnp.asarray(bary), jnp.asarray(zeros), jnp.asarray(zeros))
    one = _shade_program(scene, pts).lower(scene, pts).compile()
    monkeypatch.setattr(SHADE_MODULE, "LAYER_LANES", 4 * n)
    blocks = _shade_program(scene, pts).lower(scene, pts).compile()
    np.testing.assert_allclose(np.asarray(blocks(scene, pts)), np.asarray(one(scene, pts)),
                               rtol=1e-5, atol=1e-6, err_msg="blocks change only the sum's order")
    t_one = one.memory_analysis().temp_size_in_bytes
    t_blocks = blocks.memory_analysis().temp_size_in_bytes
    assert t_blocks * 4 < t_one, (t_blocks, t_one)
