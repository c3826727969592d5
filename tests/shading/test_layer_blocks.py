"""The shader-cost layers in blocks (``shade.layer_sum``): a launch whose layers x lanes exceed
``LAYER_LANES`` evaluates its layers in a loop of blocks, each layer exactly once, with the sum
of the single batch, and with temporaries bounded by the block rather than by every layer; and
the layered shader is the plain shader averaged over the layers' nudged normals."""

from __future__ import annotations

import dataclasses
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


def _tangent_off_normal(pts) -> np.ndarray:
    """float64[N, 3]: each point's tangent less its component along the shading normal."""
    n = np.asarray(pts.shading_normal, np.float64)
    tan = np.asarray(pts.tangent, np.float64)[:, :3]
    return tan - n * np.sum(n * tan, axis=1, keepdims=True)


def _nudged_normals(pts, n_layers: int) -> np.ndarray:
    """float64[layers, N, 3]: the layers' normals by their definition, normalize(n + a t),
    t the unit tangent made perpendicular to n, a spread over (-LAYER_NUDGE/2, LAYER_NUDGE/2)."""
    n = np.asarray(pts.shading_normal, np.float64)
    t = _tangent_off_normal(pts)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    angles = SHADE_MODULE.LAYER_NUDGE * ((np.arange(n_layers) + 0.5) / n_layers - 0.5)
    nudged = n[None] + angles[:, None, None] * t[None]
    return nudged / np.linalg.norm(nudged, axis=2, keepdims=True)


@pytest.mark.parametrize("scene_name", ["foliage", "terrain", "glass", "spheres"])
def test_the_layers_average_the_shader_over_nudged_normals(scene_name):
    # Diffuse (foliage), Lambert and GGX (terrain), Blinn-Phong (glass, spheres): the layered
    # shader, which sums its per-light terms over the layers before weighing them by colour,
    # against the plain shader run once per layer with that layer's normal, averaged.
    cost = 5
    plain = load_lit_scene(scene_name)
    rng = np.random.default_rng(21)
    n = 256
    tri = rng.integers(0, plain.faces.shape[0], n).astype(np.int32)
    bary = rng.dirichlet(np.ones(3), n).astype(np.float32)
    zeros = np.zeros((n, 3), np.float32)
    pts = jax.jit(surface_points)(plain, plain.camera, jnp.asarray(tri), jnp.asarray(bary),
                                  jnp.asarray(zeros), jnp.asarray(zeros))
    # Points whose tangent is (nearly) parallel to their normal have no nudge direction.
    keep = np.asarray(pts.valid) & (np.linalg.norm(_tangent_off_normal(pts), axis=1) > 1e-2)
    assert keep.sum() > n // 2, keep.sum()
    costly = with_shader_cost(plain, cost)
    got = np.asarray(jax.jit(shade)(pts, costly))
    shade_plain = jax.jit(shade)
    want = np.mean([np.asarray(shade_plain(dataclasses.replace(
        pts, shading_normal=jnp.asarray(normal, jnp.float32)), plain))
        for normal in _nudged_normals(pts, cost + 1)], axis=0)
    # Blinn-Phong exponents up to 4096 (spheres) magnify the normals' float32 rounding: 2.4e-5
    # of a value at most, where the shader normalized each layer's normal (1.6e-5).
    np.testing.assert_allclose(got[keep], want[keep], rtol=5e-5, atol=2e-6,
                               err_msg=f"{scene_name}: layers against the plain shader's mean")
    assert np.abs(want[keep]).max() > 0.05, "lit points, not black ones"
