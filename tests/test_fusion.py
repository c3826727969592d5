"""Kernel boundaries on XLA (jaxrender.fusion): the add-written reductions equal
jnp's, the stores return their input bit for bit and survive XLA's optimisation, and the shared
shader reduces over no short axis."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.fusion import (all_small, any_small, materialize, materialize_all, max_small,
                              sum_small)
from jaxrender.raster.resolve import pair_barycentrics
from jaxrender.shading import load_lit_scene, shade
from jaxrender.shading.vec import safe_normalize
from jaxrender.types import SurfacePoints
from tests.jaxpr_walk import all_equations, sub_jaxprs

SHORT = 4  # the longest axis the shader may reduce as adds; a reduce over one is a regression
SHADOW_MAP = 32


@pytest.mark.parametrize("shape,axis", [((7, 3), -1), ((5, 3, 4), 1), ((6, 2, 3), -1), ((3, 9), 0)])
def test_short_reductions_equal_jnp(shape, axis):
    rng = np.random.default_rng(sum(shape))
    x = rng.normal(size=shape).astype(np.float32)
    for keep in (False, True):
        np.testing.assert_allclose(jax.jit(lambda a, k=keep: sum_small(a, axis, k))(x),
                                   np.sum(x, axis=axis, keepdims=keep), rtol=1e-6, atol=1e-6,
                                   err_msg=f"sum_small over axis {axis} of {shape}, keepdims {keep}")
    b = x > -0.5
    np.testing.assert_array_equal(jax.jit(lambda a: all_small(a, axis))(b), np.all(b, axis=axis),
                                  err_msg=f"all_small over axis {axis} of {shape}")
    b = x > 0.8  # mostly False, so some rows have no True
    np.testing.assert_array_equal(jax.jit(lambda a: any_small(a, axis))(b), np.any(b, axis=axis),
                                  err_msg=f"any_small over axis {axis} of {shape}")
    np.testing.assert_array_equal(jax.jit(lambda a: max_small(a, (axis,)))(x),
                                  np.max(x, axis=axis, keepdims=True),
                                  err_msg=f"max_small over axis {axis} of {shape}")


def test_materialize_returns_its_input_bit_for_bit():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(11, 3)).astype(np.float32)
    b = rng.normal(size=(11,)).astype(np.float32)
    c = rng.normal(size=(11, 2, 2)).astype(np.float32)
    c[4, 1, 0] = np.nan
    np.testing.assert_array_equal(jax.jit(materialize)(a), a, err_msg="materialize")
    for got, want, name in zip(jax.jit(materialize_all)(a, b, c), (a, b, c), "abc"):
        np.testing.assert_array_equal(got, want, err_msg=f"materialize_all, array {name}")
    batched = jax.vmap(materialize)(np.stack([a, 2 * a]))
    np.testing.assert_array_equal(batched, np.stack([a, 2 * a]), err_msg="materialize under vmap")


def _chain(x, store):
    for i in range(6):
        x = safe_normalize(x + 0.25 * i, x)
        x = materialize(x) if store else x
    return x


def test_materialize_survives_optimisation_and_keeps_the_result():
    x = jnp.asarray(np.random.default_rng(5).normal(size=(64, 3)).astype(np.float32))
    stored = jax.jit(lambda a: _chain(a, True))
    text = stored.lower(x).compile().as_text()
    # A store survives as a scatter, or as the loop of row updates XLA:CPU's older emitters
    # (the test suite's, tests/conftest.py) expand a scatter into.
    store = re.compile(r"\b(?:scatter|dynamic-update-slice)\(")
    stores = len(store.findall(text))
    plain = len(store.findall(jax.jit(lambda a: _chain(a, False)).lower(x).compile().as_text()))
    assert stores >= plain + 6, (f"XLA removed the stores: the compiled chain has {stores} "
                                 f"stores, the chain without materialize {plain}")
    np.testing.assert_allclose(stored(x), jax.jit(lambda a: _chain(a, False))(x), rtol=1e-6,
                               atol=1e-7, err_msg="the stored chain computes another value")


def _short_reductions(jaxpr, found):
    for eqn in jaxpr.eqns:
        if eqn.primitive.name in ("reduce_sum", "reduce_and", "reduce_or", "reduce_max"):
            shape = eqn.invars[0].aval.shape
            axes = eqn.params["axes"]
            if any(shape[a] <= SHORT for a in axes):
                found.append((eqn.primitive.name, shape, axes))
        for sub in sub_jaxprs(eqn.params):
            _short_reductions(sub, found)
    return found


def _room_points(n: int, seed: int) -> SurfacePoints:
    rng = np.random.default_rng(seed)

    def unit(k):
        v = rng.normal(size=(n, k)).astype(np.float32)
        return jnp.asarray(v / np.linalg.norm(v, axis=1, keepdims=True))

    return SurfacePoints(
        position=jnp.asarray(rng.normal(size=(n, 3)), jnp.float32), normal=unit(3),
        shading_normal=unit(3), tangent=jnp.concatenate([unit(3), jnp.ones((n, 1))], 1),
        uv=jnp.asarray(rng.random((n, 2)), jnp.float32),
        duv_dx=jnp.full((n, 2), 1e-3), duv_dy=jnp.full((n, 2), 1e-3), view=unit(3),
        material=jnp.asarray(rng.integers(0, 5, n), jnp.int32),
        tri_id=jnp.zeros((n,), jnp.int32), valid=jnp.ones((n,), bool))


def test_the_shader_reduces_over_no_short_axis():
    """Every effect of the room (textures, normal map, both BRDFs, shadows, three lights): a
    reduce over a size-3 axis would cut the shader into a kernel there."""
    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    closed = jax.make_jaxpr(lambda p: shade(p, scene))(_room_points(16, 9))
    found = _short_reductions(closed.jaxpr, [])
    assert not found, f"shade() reduces over short axes: {found}"


# Views and lookups of a point's rows; anything else is arithmetic.
NOT_ARITHMETIC = ("slice", "squeeze", "broadcast_in_dim", "reshape", "gather", "pjit", "jit")


def _wide_arithmetic(jaxpr, scope: str, skip: str, found):
    """Equations under named scope ``scope`` (not under ``skip``) computing arrays of more than
    one axis."""
    for eqn in jaxpr.eqns:
        stack = str(eqn.source_info.name_stack)
        if (scope in stack.split("/") and skip not in stack
                and eqn.primitive.name not in NOT_ARITHMETIC
                and any(len(v.aval.shape) > 1 for v in eqn.outvars)):
            found.append((stack, eqn.primitive.name, [v.aval.shape for v in eqn.outvars]))
        for sub in sub_jaxprs(eqn.params):
            _wide_arithmetic(sub, scope, skip, found)
    return found


def test_the_lights_compute_one_value_a_point():
    """The lights' terms are per-point components (``vec.components``): arithmetic on an
    [N, 3] or [N, L, 3] array there makes each colour channel's kernel recompute the terms the
    three channels share, and XLA stores them between kernels instead (room's shader wrote 443
    bytes a point). The shadow lookup's light-space transform is exempt: it is one matrix."""
    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    closed = jax.make_jaxpr(lambda p: shade(p, scene))(_room_points(16, 9))
    found = _wide_arithmetic(closed.jaxpr, "lights", "shadow_lookup", [])
    assert not found, f"the lights compute on arrays of several axes: {found[:5]}"


def test_pair_barycentrics_reduce_over_no_short_axis():
    """Forward's fragments and transparent layers feed the shader through these: a reduce here
    would cut their shading launch into kernels again."""
    rng = np.random.default_rng(11)
    clip = jnp.asarray(np.concatenate([rng.normal(size=(6, 3)), np.ones((6, 1))], 1), jnp.float32)
    faces = jnp.asarray([[0, 1, 2], [3, 4, 5]], jnp.int32)
    tri = jnp.asarray([0, 1, -1, 0], jnp.int32)
    px = py = jnp.asarray([3, 1, 0, 7], jnp.int32)
    closed = jax.make_jaxpr(lambda c: pair_barycentrics(c, faces, tri, px, py, 16, 16))(clip)
    found = _short_reductions(closed.jaxpr, [])
    assert not found, f"pair_barycentrics reduces over short axes: {found}"


def _scatter_sources(jaxpr, producers, found):
    """(scatter primitive, the primitive that made its updates) for every scatter, through
    nested jaxprs (loops, branches, calls: their inner variables are their own)."""
    made = dict(producers)
    for eqn in jaxpr.eqns:
        if eqn.primitive.name.startswith("scatter"):
            updates = eqn.invars[2]
            found.append((eqn.primitive.name, made.get(updates, "input")))
        for v in eqn.outvars:
            made[v] = eqn.primitive.name
        for sub in sub_jaxprs(eqn.params):
            _scatter_sources(sub, {}, found)
    return found


def _points_of(n: int):
    def points_of(items):
        pts = _room_points(n, 4)
        return jax.tree.map(lambda a: a[items % n], pts)
    return points_of


@pytest.mark.parametrize("mode", ["blocks", "switch"])
def test_the_dispatch_scatters_shader_results_computed_whole(monkeypatch, mode):
    """A scatter evaluates a fused operand once per element it writes, so the shader's lights
    ran once per colour channel inside the dispatch's scatter (the offline H100 program,
    RESULTS.md, thirty-sixth session): its values must reach the scatter through
    ``whole_rows``'s barrier, as a tensor computed on its own."""
    import jaxrender.pipelines.dispatch as dispatch

    monkeypatch.setenv(dispatch.ENV_LAUNCH, mode)
    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    n = 64
    work = dispatch.WorkList.of(jnp.arange(n) % 3 != 0)
    closed = jax.make_jaxpr(lambda w: dispatch.shade(
        w, _points_of(n), lambda p: shade(p, scene), jnp.zeros((n, 3)), 16))(work)
    sources = [s for _, s in _scatter_sources(closed.jaxpr, {}, [])]
    assert "optimization_barrier" in sources, f"no scatter reads barrier output: {sources}"
    assert all(s != "concatenate" for s in sources), (
        f"a scatter reads the shader's stacked channels directly: {sources}")


def test_the_dense_launch_scatters_shader_results_computed_whole():
    import jaxrender.pipelines.dispatch as dispatch

    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    n = 64
    active = jnp.arange(n) % 5 == 0  # fits the half-size tier: compacted and scattered back
    closed = jax.make_jaxpr(lambda a: dispatch.shade_dense(
        a, _points_of(n), lambda p: shade(p, scene), jnp.zeros((n, 3))))(active)
    found = _scatter_sources(closed.jaxpr, {}, [])
    unique = [s for name, s in found if name == "scatter"]
    assert "optimization_barrier" in unique, f"the compacted tier scatters {found}"


def test_the_layer_shader_joins_channels_computed_apart():
    """Its five channels in one fusion ran the lights once per channel (a loop fusion writes
    an element a thread); the colour, opacity and depth are computed apart and then joined."""
    from jaxrender.pipelines.transparency import layer_shader

    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    closed = jax.make_jaxpr(layer_shader(scene, scene.camera))(_room_points(16, 2))
    made = {}
    for eqn in closed.jaxpr.eqns:
        for v in eqn.outvars:
            made[v] = eqn
    last = made[closed.jaxpr.outvars[0]]
    assert last.primitive.name == "concatenate", last.primitive.name

    def origin(v):  # through the reshapes and broadcasts that add the channel axis
        eqn = made.get(v)
        while eqn is not None and eqn.primitive.name in ("broadcast_in_dim", "reshape"):
            eqn = made.get(eqn.invars[0])
        return eqn.primitive.name if eqn is not None else "input"

    assert [origin(v) for v in last.invars] == ["optimization_barrier"] * 3, (
        [origin(v) for v in last.invars])


def test_the_layer_shader_filters_the_texture_once():
    """Its radiance and its opacity both read the points' filtered texture: looked up once and
    stored, not once for each (XLA filtered it again in each of their fusions)."""
    from jaxrender.pipelines.transparency import layer_shader
    from jaxrender.shading import opacity, texture_sample

    scene = load_lit_scene("room", effects={"shadow_map_size": SHADOW_MAP})
    texels = scene.textures.atlas.size // 4  # the atlas's RGBA texels, read as rows
    points = _room_points(16, 3)

    def texture_reads(fn):
        closed = jax.make_jaxpr(fn)(points)
        return sum(eqn.primitive.name == "gather" and eqn.invars[0].aval.shape == (texels, 4)
                   for eqn in all_equations(closed.jaxpr))

    one_lookup = texture_reads(lambda p: texture_sample(p, scene))
    assert one_lookup > 0, "the texture lookup reads no texel"
    assert texture_reads(lambda p: opacity(p, scene)) == one_lookup
    # The room's shader also reads its normal map from the atlas: the layer shader reads what
    # shade() alone reads, and the opacity adds no lookup of its own.
    assert texture_reads(layer_shader(scene, scene.camera)) == texture_reads(
        lambda p: shade(p, scene)), "the layer shader filters the texture more than once"
    values = layer_shader(scene, scene.camera)(points)
    np.testing.assert_allclose(values[:, 3], opacity(points, scene), rtol=1e-6, atol=0,
                               err_msg="the layer's opacity is not the shared opacity()")
    np.testing.assert_allclose(values[:, :3], shade(points, scene), rtol=1e-6, atol=1e-7,
                               err_msg="the layer's radiance is not the shared shade()")
