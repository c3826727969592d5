"""Effects are static: switching one off removes its work from the compiled program."""

import jax
from shading_helpers import plane_scene, points

from jaxrender.scene import Material
from jaxrender.shading import shade
from jaxrender.scene.scene import ShadowMap

import jax.numpy as jnp


def _hlo(scene, effects):
    p = points(8)
    return jax.jit(lambda p, s: shade(p, s, effects)).lower(p, scene).as_text(debug_info=True)


def _count(text, op):
    return text.count(op)


def _scene():
    s = plane_scene([Material("m", albedo=(0.5,) * 3, texture=0, normal_map=1, specular=(0.3,) * 3,
                              shininess=50.0, brdf="blinn_phong", emissive=(0.1, 0.0, 0.0))],
                    textures=[jnp.ones((4, 4, 4)), jnp.ones((4, 4, 4))],
                    directional=[((0, 1, 0), 1.0)], point=[((0, 1, 0), 1.0)])
    sm = ShadowMap(depth=jnp.ones((8, 8)), origin=jnp.zeros(3), basis=jnp.eye(3),
                   half_extent=jnp.ones(3))
    import dataclasses
    return dataclasses.replace(s, shadow=sm)


def test_each_effect_removes_work_when_off():
    scene = _scene()
    full = scene.effects.replace(shadows=True, toksvig=True)
    base = _hlo(scene, full)
    assert "shadow_lookup" in base, "the shadow lookup should be traced when shadows are on"
    no_shadow = _hlo(scene, full.replace(shadows=False))
    assert "shadow_lookup" not in no_shadow, "shadows off must compile no shadow lookup"
    for flag in ("textures", "normal_map", "shadows"):
        off = _hlo(scene, full.replace(**{flag: False}))
        assert _count(off, "gather") < _count(base, "gather"), f"{flag} off: fewer gathers"
    for flag in ("specular", "emissive"):
        off = _hlo(scene, full.replace(**{flag: False}))
        assert len(off) < len(base), f"{flag} off should shrink the program"
    assert "while" not in base


def _flops(scene, effects, n=64):
    p = points(n)
    compiled = jax.jit(lambda p, s: shade(p, s, effects)).lower(p, scene).compile()
    analysis = compiled.cost_analysis()
    return (analysis[0] if isinstance(analysis, list) else analysis)["flops"]


def test_shader_cost_layers_are_work_not_loop_overhead():
    """Layers are batched, not looped (a loop's per-layer round trip would cost as much on a
    few lanes as on many), and each layer adds the same work: flops linear in the layers."""
    scene = _scene()
    full = scene.effects.replace(shadows=True, toksvig=True)
    assert "while" not in _hlo(scene, full.replace(shader_cost=3)), "layers must not loop"
    f = {c: _flops(scene, full.replace(shader_cost=c)) for c in (1, 3, 7)}
    per_layer_low, per_layer_high = (f[3] - f[1]) / 2, (f[7] - f[3]) / 4
    assert per_layer_low > 0, f
    assert abs(per_layer_high / per_layer_low - 1) < 0.05, f"flops not linear in layers: {f}"
