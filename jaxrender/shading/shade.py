"""The one shared shader: ``shade(points, scene, effects) -> linear RGB``.

Every effect is a static Python branch on ``effects`` (a frozen dataclass): a scene without
shadows traces no shadow lookup, one without textures no texture gather, and so on.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrender.fusion import materialize, materialize_all, sum_small
from jaxrender.scene.effects import BLINN_PHONG, GGX, PROC_STRIPES, Effects
from jaxrender.scene.scene import Scene
import jaxrender.shading.brdf as brdf
from jaxrender.shading.shadow import shadow_factor
from jaxrender.shading.texture import sample
from jaxrender.shading.vec import cross, dot, safe_normalize
from jaxrender.types import Array, SurfacePoints

LAYER_NUDGE = 1e-3  # radians; the spread of the shader-cost layers' normals
# The most layer evaluations (layers x lanes) batched at once: XLA stores each layer's
# intermediates, about 90 bytes a layer and lane for room's shader (CPU memory analysis), so
# this bounds them near 17 GiB; a 2^17-lane chunk at cost 1024 (the studies' highest) is still
# one batch. A 1920x1080 screen at cost 1024 in one launch needed 177 GiB.
LAYER_LANES = 3 << 26


def _gather(x: Array, idx: Array) -> Array:
    return x[idx]


def _base_colour(points: SurfacePoints, scene: Scene, effects: Effects) -> tuple[Array, Array]:
    """Albedo [N, 3] and alpha [N] after textures and the procedural shader."""
    m = scene.materials
    mat = points.material
    albedo = _gather(m.albedo, mat)
    alpha = _gather(m.alpha, mat)
    if effects.textures:
        tid = _gather(m.texture, mat)
        texel = sample(scene.textures, tid, points.uv, points.duv_dx, points.duv_dy,
                       effects.aniso_taps)
        has = (tid >= 0)
        albedo = albedo * jnp.where(has[:, None], texel[:, :3], 1.0)
        alpha = alpha * jnp.where(has, texel[:, 3], 1.0)
    if effects.procedural:
        # Oxide's stripe shader: IntTexCoord.x % 2 == 0 ? 1 : 0 at the material's resolution.
        res = _gather(m.stripe_resolution, mat)
        texel_x = jnp.floor(points.uv[:, 0] * res)
        stripe = jnp.where(jnp.mod(texel_x, 2.0) == 0.0, 1.0, 0.0).astype(jnp.float32)
        is_proc = _gather(m.procedural, mat) == PROC_STRIPES
        albedo = albedo * jnp.where(is_proc, stripe, 1.0)[:, None]
    return albedo, alpha


@jax.named_scope("alpha")
def alpha(points: SurfacePoints, scene: Scene, effects: Effects | None = None) -> Array:
    """Opacity float32[N]: material alpha times the filtered texture alpha."""
    effects = scene.effects if effects is None else effects
    m = scene.materials
    a = _gather(m.alpha, points.material)
    if effects.textures:
        tid = _gather(m.texture, points.material)
        texel = sample(scene.textures, tid, points.uv, points.duv_dx, points.duv_dy,
                       effects.aniso_taps)
        a = a * jnp.where(tid >= 0, texel[:, 3], 1.0)
    return a


@jax.named_scope("opacity")
def opacity(points: SurfacePoints, scene: Scene, effects: Effects | None = None) -> Array:
    """Opacity float32[N] of blended materials: the material's opacity, times the filtered
    texture alpha where its opacity_source is "texture_alpha"; 1 for opaque materials."""
    effects = scene.effects if effects is None else effects
    m = scene.materials
    a = _gather(m.opacity, points.material)
    if effects.textures:
        tid = _gather(m.texture, points.material)
        from_tex = _gather(m.opacity_texture, points.material) & (tid >= 0)
        texel = sample(scene.textures, tid, points.uv, points.duv_dx, points.duv_dy,
                       effects.aniso_taps)
        a = a * jnp.where(from_tex, texel[:, 3], 1.0)
    return a


def alpha_test(points: SurfacePoints, scene: Scene, effects: Effects | None = None) -> Array:
    """bool[N]: True where the point survives the alpha test (always, unless effects.alpha_test;
    for alpha-tested materials alpha >= alpha_cutoff). Invalid points are False."""
    effects = scene.effects if effects is None else effects
    if not effects.alpha_test:
        return points.valid
    m = scene.materials
    tested = _gather(m.alpha_tested, points.material)
    keep = alpha(points, scene, effects) >= _gather(m.alpha_cutoff, points.material)
    return points.valid & (~tested | keep)


def _normal_map(points: SurfacePoints, scene: Scene, effects: Effects) -> tuple[Array, Array]:
    """Shading normal after the normal map [N, 3] and the filtered normal length [N, 1]."""
    n = points.shading_normal
    nid = _gather(scene.materials.normal_map, points.material)
    texel = sample(scene.textures, nid, points.uv, points.duv_dx, points.duv_dy, effects.aniso_taps)
    nt = texel[:, :3] * 2.0 - 1.0  # tangent space, shortened by filtering
    length = jnp.sqrt(dot(nt, nt))
    helper = jnp.where(jnp.abs(n[:, 0:1]) < 0.9, jnp.asarray([[1.0, 0.0, 0.0]]),
                       jnp.asarray([[0.0, 1.0, 0.0]]))
    t = points.tangent[:, :3]
    t = safe_normalize(t - n * dot(n, t), safe_normalize(cross(n, helper), helper))
    b = cross(n, t) * jnp.where(points.tangent[:, 3:4] < 0.0, -1.0, 1.0)
    mapped = safe_normalize(nt[:, 0:1] * t + nt[:, 1:2] * b + nt[:, 2:3] * n, n)
    has = (nid >= 0)[:, None]
    return jnp.where(has, mapped, n), jnp.where(has, jnp.clip(length, 0.0, 1.0), 1.0)


@jax.named_scope("lights")
def _incoming(points: SurfacePoints, scene: Scene, effects: Effects):
    """(direction to each light l, its irradiance E, shadows included), float32[N, L, 3] each,
    or None for a scene without lights: what the lobes need besides the shading normal."""
    lt = scene.lights
    pos, ng = points.position, points.normal
    ls, es = [], []
    if lt.dir_to_light.shape[0]:
        ld = jnp.broadcast_to(lt.dir_to_light[None], (pos.shape[0],) + lt.dir_to_light.shape)
        ed = jnp.broadcast_to(lt.dir_irradiance[None], ld.shape)
        if effects.shadows:
            if scene.shadow is None:
                raise ValueError(f"scene {scene.name!r}: effects.shadows is on but the scene has "
                                 "no shadow map; call jaxrender.shading.with_shadow_map(scene)")
            vis = shadow_factor(scene.shadow, pos, ng, effects.shadow_bias)  # light 0 only
            first = jnp.arange(lt.dir_to_light.shape[0]) == 0
            ed = ed * jnp.where(first[None, :, None], vis[:, :, None], 1.0)
        ls.append(ld)
        es.append(ed)
    if lt.point_position.shape[0]:
        d = lt.point_position[None, :, :] - pos[:, None, :]  # [N, Lp, 3]
        dist2 = jnp.maximum(dot(d, d), 1e-12)
        ls.append(d / jnp.sqrt(dist2))
        es.append(lt.point_intensity[None, :, :] / dist2)
    if not ls:
        return None
    return jnp.concatenate(ls, axis=1), jnp.concatenate(es, axis=1)


@jax.named_scope("lights")
def _light_sum(points: SurfacePoints, scene: Scene, effects: Effects, n: Array, albedo: Array,
               spec_params, incoming) -> Array:
    """Sum over all directional and point lights of f(l, v) E cos at shading normal n,
    float32[N, 3], given ``_incoming``'s terms."""
    if incoming is None:
        return jnp.zeros_like(albedo)
    l_dir, e = incoming
    ng, v, mat = points.normal, points.view, points.material
    n_l = n[:, None, :]
    cos = dot(n_l, l_dir)  # [N, L, 1]
    above = dot(ng[:, None, :], l_dir) > 0.0
    cos_c = jnp.where(above, jnp.maximum(cos, 0.0), 0.0)
    f = brdf.lambert(albedo)[:, None, :]
    if effects.specular:
        ks, shin, alpha_g = spec_params
        kind = _gather(scene.materials.brdf, mat)[:, None, None]
        h = safe_normalize(l_dir + v[:, None, :], n_l + 0.0 * l_dir)
        n_h = dot(n_l, h)
        if BLINN_PHONG in effects.brdfs:
            bp = brdf.blinn_phong(ks[:, None, :], shin[:, None, :], n_h)
            f = f + jnp.where(kind == BLINN_PHONG, bp, 0.0)
        if GGX in effects.brdfs:
            n_v = dot(n, v)[:, None, :]
            v_h = dot(v[:, None, :], h)
            g = brdf.ggx(ks[:, None, :], alpha_g[:, None, :], cos, n_v, n_h, v_h)
            f = f + jnp.where(kind == GGX, g, 0.0)
    return sum_small(f * e * cos_c, axis=1)


def layer_sum(layer, angles: Array, lanes: int) -> Array:
    """sum_k layer(angles[k]) for a ``layer`` over ``lanes`` points: batched over the layers
    (vmap), in blocks of as many layers as keep a block's evaluations within LAYER_LANES. All
    the layers in one block need no loop; more run in a ``fori_loop`` of whole blocks, whose
    iterations each read back to the host on a GPU (about 27 us) but evaluate over LAYER_LANES
    / 2 layer-lanes apiece. Each layer is evaluated exactly once: those left over from the
    last whole block run after the loop."""
    n_layers = angles.shape[0]
    block = max(1, LAYER_LANES // max(int(lanes), 1))
    if n_layers <= block:
        return jnp.sum(jax.vmap(layer)(angles), axis=0)
    n_blocks = n_layers // block

    def add_block(i, acc):
        some = jax.lax.dynamic_slice_in_dim(angles, i * block, block)
        return acc + jnp.sum(jax.vmap(layer)(some), axis=0)

    one = jax.eval_shape(layer, angles[0])
    total = jax.lax.fori_loop(0, n_blocks, add_block, jnp.zeros(one.shape, one.dtype))
    if n_layers > n_blocks * block:
        total = total + jnp.sum(jax.vmap(layer)(angles[n_blocks * block:]), axis=0)
    return total


@jax.named_scope("shade")
def shade(points: SurfacePoints, scene: Scene, effects: Effects | None = None) -> Array:
    """Outgoing linear RGB radiance float32[N, 3] towards ``points.view``; 0 for invalid points.

    L = sum_lights f(l, v) E_l cos + albedo * ambient + emissive, f = albedo / pi + a specular
    lobe per the material's BRDF kind. ``effects`` defaults to ``scene.effects``.
    """
    effects = scene.effects if effects is None else effects
    m = scene.materials
    mat = points.material
    albedo, _ = _base_colour(points, scene, effects)
    if effects.textures:
        # Stored: every light's lobe reads it, and a fused read would filter the texture again.
        albedo = materialize(albedo)
    n = points.shading_normal
    spec_params = None
    if effects.specular:
        ks = _gather(m.specular, mat)
        shin = _gather(m.shininess, mat)[:, None]
        alpha_g = jnp.square(_gather(m.roughness, mat))[:, None]
        spec_params = (ks, shin, alpha_g)
    if effects.normal_map:
        n, length = materialize_all(*_normal_map(points, scene, effects))
        if effects.toksvig and effects.specular:
            spec_params = (ks, brdf.toksvig_shininess(shin, length),
                           brdf.toksvig_roughness(alpha_g, length))
    layers = 1 + effects.shader_cost
    if layers == 1:
        direct = _light_sum(points, scene, effects, n, albedo, spec_params,
                            _incoming(points, scene, effects))
    else:
        # Shader-cost layers: the lights again with the normal nudged along the tangent by
        # a layer-dependent angle (< LAYER_NUDGE), so XLA cannot hoist or merge the layers.
        t = safe_normalize(points.tangent[:, :3] - n * dot(n, points.tangent[:, :3]), n)
        angles = LAYER_NUDGE * ((jnp.arange(layers, dtype=jnp.float32) + 0.5) / layers - 0.5)

        # What every layer shares (the lights' directions and irradiance, the shadow lookups
        # among them, and the point's frame), computed and stored once: fused into the batched
        # layers, XLA computed it again for each layer.
        incoming = _incoming(points, scene, effects)
        if incoming is not None:
            l_dir, e = incoming
            l_dir, e, n, t, albedo, ng, v = materialize_all(l_dir, e, n, t, albedo,
                                                            points.normal, points.view)
            incoming = (l_dir, e)
            points = dataclasses.replace(points, normal=ng, view=v)

        def layer(ang):
            n_i = safe_normalize(n + t * ang, n)
            return _light_sum(points, scene, effects, n_i, albedo, spec_params, incoming)

        direct = layer_sum(layer, angles, n.shape[0]) / layers
    rgb = direct + albedo * scene.lights.ambient[None, :]
    if effects.emissive:
        rgb = rgb + _gather(m.emissive, mat)
    rgb = jnp.where(jnp.isfinite(rgb), rgb, 0.0)
    return jnp.where(points.valid[:, None], rgb, 0.0)
