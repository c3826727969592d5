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
    costly = _hlo(scene, full.replace(shader_cost=3))
    assert "while" in costly, "shader_cost > 0 runs its layers in a loop"
