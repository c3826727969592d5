"""The one shared shader: ``shade(points, scene, effects) -> linear RGB``.

Every effect is a static Python branch on ``effects`` (a frozen dataclass): a scene without
shadows traces no shadow lookup, one without textures no texture gather, and so on.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.fusion import materialize, materialize_all
from jaxrender.scene.effects import BLINN_PHONG, GGX, PROC_STRIPES, Effects
from jaxrender.scene.scene import Scene
import jaxrender.shading.brdf as brdf
from jaxrender.shading.shadow import shadow_factor
from jaxrender.shading.texture import sample
from jaxrender.shading.vec import components, cross3, dot3, normalize3, stack
from jaxrender.types import Array, SurfacePoints

LAYER_NUDGE = 1e-3  # radians; the spread of the shader-cost layers' normals
# The most layer evaluations (layers x lanes) batched at once: XLA stores each layer's
# intermediates, about 90 bytes a layer and lane for room's shader (CPU memory analysis), so
# this bounds them near 17 GiB; a 2^17-lane chunk at cost 1024 (the studies' highest) is still
# one batch. A 1920x1080 screen at cost 1024 in one launch needed 177 GiB.
LAYER_LANES = 3 << 26


def _gather(x: Array, idx: Array) -> Array:
    return x[idx]


def texture_sample(points: SurfacePoints, scene: Scene, effects: Effects | None = None) -> Array:
    """The filtered texture lookup float32[N, 4] of each point's material texture (any value
    where the material has none): what ``shade`` and ``opacity`` read, for a caller that runs
    both on the same points to hand them one lookup."""
    effects = scene.effects if effects is None else effects
    return sample(scene.textures, _gather(scene.materials.texture, points.material), points.uv,
                  points.duv_dx, points.duv_dy, effects.aniso_taps)


def _base_colour(points: SurfacePoints, scene: Scene, effects: Effects,
                 texel: Array | None = None) -> tuple[Array, Array]:
    """Albedo [N, 3] and alpha [N] after textures and the procedural shader."""
    m = scene.materials
    mat = points.material
    albedo = _gather(m.albedo, mat)
    alpha = _gather(m.alpha, mat)
    if effects.textures:
        tid = _gather(m.texture, mat)
        texel = texture_sample(points, scene, effects) if texel is None else texel
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
        a = a * jnp.where(tid >= 0, texture_sample(points, scene, effects)[:, 3], 1.0)
    return a


@jax.named_scope("opacity")
def opacity(points: SurfacePoints, scene: Scene, effects: Effects | None = None,
            texel: Array | None = None) -> Array:
    """Opacity float32[N] of blended materials: the material's opacity, times the filtered
    texture alpha where its opacity_source is "texture_alpha"; 1 for opaque materials.
    ``texel``: the points' ``texture_sample``, when the caller has it."""
    effects = scene.effects if effects is None else effects
    m = scene.materials
    a = _gather(m.opacity, points.material)
    if effects.textures:
        tid = _gather(m.texture, points.material)
        from_tex = _gather(m.opacity_texture, points.material) & (tid >= 0)
        texel = texture_sample(points, scene, effects) if texel is None else texel
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
    n = components(points.shading_normal)
    nid = _gather(scene.materials.normal_map, points.material)
    texel = sample(scene.textures, nid, points.uv, points.duv_dx, points.duv_dy, effects.aniso_taps)
    # Stored: each of the four values stored below reads it, and a fused read filtered the
    # normal map again for each (the reference on room: 4.4 ms of filtering a frame, not 1.3).
    nt = components(materialize(texel[:, :3]))
    nt = tuple(c * 2.0 - 1.0 for c in nt)  # tangent space, shortened by filtering
    length = jnp.sqrt(dot3(nt, nt))
    one, zero = jnp.float32(1.0), jnp.float32(0.0)
    x_helper = jnp.abs(n[0]) < 0.9
    helper = (jnp.where(x_helper, one, zero), jnp.where(x_helper, zero, one), zero)
    t = components(points.tangent)[:3]
    t = normalize3(tuple(a - c * dot3(n, t) for a, c in zip(t, n)),
                   normalize3(cross3(n, helper), helper))
    sign = jnp.where(points.tangent[:, 3] < 0.0, -1.0, 1.0)
    b = tuple(c * sign for c in cross3(n, t))
    mapped = normalize3(tuple(nt[0] * tc + nt[1] * bc + nt[2] * nc
                              for tc, bc, nc in zip(t, b, n)), n)
    has = nid >= 0
    return (stack(tuple(jnp.where(has, m, c) for m, c in zip(mapped, n))),
            jnp.where(has, jnp.clip(length, 0.0, 1.0), 1.0)[:, None])


@jax.named_scope("lights")
def _incoming(points: SurfacePoints, scene: Scene, effects: Effects) -> list:
    """Per light, directional lights first: (direction to the light, its irradiance E with
    shadows), each a component tuple (``vec.components``) of float32[N] or scalars: what the
    lobes need besides the shading normal. Empty for a scene without lights."""
    lt = scene.lights
    out = []
    for j in range(lt.dir_to_light.shape[0]):
        e = components(lt.dir_irradiance[j])
        if effects.shadows and j == 0:  # the shadow map is the first directional light's
            if scene.shadow is None:
                raise ValueError(f"scene {scene.name!r}: effects.shadows is on but the scene has "
                                 "no shadow map; call jaxrender.shading.with_shadow_map(scene)")
            vis = shadow_factor(scene.shadow, points.position, points.normal,
                                effects.shadow_bias)[:, 0]
            e = tuple(c * vis for c in e)
        out.append((components(lt.dir_to_light[j]), e))
    pos = components(points.position)
    for j in range(lt.point_position.shape[0]):
        d = tuple(q - p for q, p in zip(components(lt.point_position[j]), pos))
        dist2 = jnp.maximum(dot3(d, d), 1e-12)
        root = jnp.sqrt(dist2)
        out.append((tuple(c / root for c in d),
                    tuple(c / dist2 for c in components(lt.point_intensity[j]))))
    return out


class PointFrame(NamedTuple):
    """What the lobes read of a point besides its shading normal: the geometric normal and the
    view direction (component tuples), the material, and whether the point is live (unused by
    the lobes; it lets a test count the live lanes each layer evaluation runs)."""

    normal: tuple
    view: tuple
    material: Array
    valid: Array


def _half_vectors(frame: PointFrame, incoming: list, n: tuple) -> list:
    """Per light, the half vector between it and the view (``n`` where they are opposite)."""
    return [normalize3(tuple(a + b for a, b in zip(l_dir, frame.view)), n)
            for l_dir, _ in incoming]


@jax.named_scope("lights")
def _light_terms(frame: PointFrame, scene: Scene, effects: Effects, n: tuple, spec_params,
               incoming: list, halves: list | None) -> list:
    """Per light, what depends on the shading normal ``n`` (float32[N] each): the clamped
    cosine, and times it the Blinn-Phong lobe for a unit ks and GGX's D V (None without
    specular lobes); ``_lit`` weighs them by colour. The shader-cost layers sum these over
    their nudged normals before weighing: one scalar a term, so XLA computes each layer's
    terms inside the sum rather than storing them for every layer and point."""
    ng, v = frame.normal, frame.view
    out = []
    for j, (l_dir, _) in enumerate(incoming):
        cos = dot3(n, l_dir)
        cos_c = jnp.where(dot3(ng, l_dir) > 0.0, jnp.maximum(cos, 0.0), 0.0)
        phong = ggx = None
        if effects.specular:
            _, shin, alpha_g = spec_params
            n_h = dot3(n, halves[j])
            if BLINN_PHONG in effects.brdfs:
                phong = brdf.blinn_phong(1.0, shin, n_h) * cos_c
            if GGX in effects.brdfs:
                ggx = brdf.ggx_dv(alpha_g, cos, dot3(n, v), n_h) * cos_c
        out.append((cos_c, phong, ggx))
    return out


def _lit(terms: list, frame: PointFrame, scene: Scene, effects: Effects, albedo: tuple,
         spec_params, incoming: list, halves: list | None) -> tuple:
    """Sum over all directional and point lights of f(l, v) E cos, per colour channel (a
    component tuple of float32[N]), from ``_light_terms``'s terms: E (albedo / pi cos + ks
    phong + F ggx), F Schlick's Fresnel of ks at the half vector."""
    total = tuple(jnp.zeros_like(a) for a in albedo)
    if effects.specular:
        ks = spec_params[0]
        kind = _gather(scene.materials.brdf, frame.material)
    for j, ((_, e), (cos_c, phong, ggx)) in enumerate(zip(incoming, terms)):
        f = [brdf.lambert(a) * cos_c for a in albedo]
        if phong is not None:
            f = [fc + jnp.where(kind == BLINN_PHONG, k * phong, 0.0) for fc, k in zip(f, ks)]
        if ggx is not None:
            v_h = dot3(frame.view, halves[j])
            f = [fc + jnp.where(kind == GGX, brdf.schlick(k, v_h) * ggx, 0.0)
                 for fc, k in zip(f, ks)]
        total = tuple(a + fc * ec for a, fc, ec in zip(total, f, e))
    return total


def _store(tree, n: int):
    """``materialize_all`` of the float32[n] leaves of ``tree`` (scalars and integers stay as
    they are)."""
    leaves, treedef = jax.tree.flatten(tree)
    per_point = [i for i, a in enumerate(leaves)
                 if jnp.shape(a) == (n,) and jnp.result_type(a) == jnp.float32]
    stored = materialize_all(*(leaves[i] for i in per_point))
    for i, a in zip(per_point, stored):
        leaves[i] = a
    return jax.tree.unflatten(treedef, leaves)


def summed_over_layers(tree):
    """Each leaf of ``tree`` summed over its leading (layer) axis, the leaves of one shape and
    type in one reduction of them stacked: reduced leaf by leaf, they were separate kernels
    that each read a term the layers share, and XLA stored that term for every layer and lane
    so that each could."""
    leaves, treedef = jax.tree.flatten(tree)
    groups: dict = {}
    for i, x in enumerate(leaves):
        groups.setdefault((x.shape, x.dtype), []).append(i)
    sums = [None] * len(leaves)
    for members in groups.values():
        total = jnp.sum(jnp.stack([leaves[i] for i in members], axis=-1), axis=0)
        for k, i in enumerate(members):
            sums[i] = total[..., k]
    return jax.tree.unflatten(treedef, sums)


def layer_sum(layer, angles: Array, lanes: int):
    """sum_k layer(angles[k]) (an array, or a pytree of them, each leaf summed) for a
    ``layer`` over ``lanes`` points: batched over the layers (vmap), in blocks of as many
    layers as keep a block's evaluations within LAYER_LANES. All
    the layers in one block need no loop; more run in a ``fori_loop`` of whole blocks, whose
    iterations each read back to the host on a GPU (about 27 us) but evaluate over LAYER_LANES
    / 2 layer-lanes apiece. Each layer is evaluated exactly once: those left over from the
    last whole block run after the loop."""
    n_layers = angles.shape[0]
    block = max(1, LAYER_LANES // max(int(lanes), 1))

    def batch(some):  # the layers of ``some`` evaluated together and summed
        return summed_over_layers(jax.vmap(layer)(some))

    def add(a, b):
        return jax.tree.map(jnp.add, a, b)

    if n_layers <= block:
        return batch(angles)
    n_blocks = n_layers // block

    def add_block(i, acc):
        return add(acc, batch(jax.lax.dynamic_slice_in_dim(angles, i * block, block)))

    zeros = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), jax.eval_shape(layer, angles[0]))
    total = jax.lax.fori_loop(0, n_blocks, add_block, zeros)
    if n_layers > n_blocks * block:
        total = add(total, batch(angles[n_blocks * block:]))
    return total


def _layered_terms(points, scene, effects, n, spec_params, incoming, halves, albedo, frame):
    """``_light_terms``'s terms averaged over 1 + shader_cost layers, each with the normal nudged
    along the tangent by its own angle (< LAYER_NUDGE), so XLA cannot hoist or merge them;
    and the per-point inputs of ``_lit``, stored once."""
    shared_out = (incoming, halves, albedo, spec_params, frame)
    if not incoming:  # no lights: no terms to sum
        return [], shared_out
    layers = 1 + effects.shader_cost
    tangent = components(points.tangent)[:3]
    zero = tuple(jnp.zeros_like(c) for c in n)
    t = normalize3(tuple(a - c * dot3(n, tangent) for a, c in zip(tangent, n)), zero)
    angles = LAYER_NUDGE * ((jnp.arange(layers, dtype=jnp.float32) + 0.5) / layers - 0.5)
    # |n + ang t| = sqrt(1 + ang^2) for the unit n and its unit perpendicular t (0 where the
    # tangent is degenerate): each layer's normal is scaled by a constant of the layer. A
    # square root per layer and point made XLA store each layer's terms for every point
    # rather than compute them inside the sum.
    scales = jax.lax.rsqrt(1.0 + jnp.square(angles))
    # What every layer shares (the lights' directions and irradiance, the shadow lookups
    # among them, the half vectors, the lobes' parameters and the point's frame), computed
    # and stored once: fused into the batched layers, XLA computed it again for each layer.
    incoming, halves, n, t, albedo, spec_params, frame = _store(
        (incoming, halves, n, t, albedo, spec_params, frame), points.material.shape[0])

    def layer(ang_scale):
        ang, scale = ang_scale[0], ang_scale[1]
        n_i = tuple((a + b * ang) * scale for a, b in zip(n, t))
        return _light_terms(frame, scene, effects, n_i, spec_params, incoming, halves)

    sums = layer_sum(layer, jnp.stack([angles, scales], axis=1), points.material.shape[0])
    return (jax.tree.map(lambda x: x / layers, sums),
            (incoming, halves, albedo, spec_params, frame))


@jax.named_scope("shade")
def shade(points: SurfacePoints, scene: Scene, effects: Effects | None = None,
          texel: Array | None = None) -> Array:
    """Outgoing linear RGB radiance float32[N, 3] towards ``points.view``; 0 for invalid points.

    L = sum_lights f(l, v) E_l cos + albedo * ambient + emissive, f = albedo / pi + a specular
    lobe per the material's BRDF kind. ``effects`` defaults to ``scene.effects``; ``texel``:
    the points' ``texture_sample``, when the caller has it.
    """
    effects = scene.effects if effects is None else effects
    m = scene.materials
    mat = points.material
    albedo, _ = _base_colour(points, scene, effects, texel)
    if effects.textures:
        # Stored: every light's lobe reads it, and a fused read would filter the texture again.
        albedo = materialize(albedo)
    n = points.shading_normal
    spec_params = None
    if effects.specular:
        ks = components(_gather(m.specular, mat))
        shin = _gather(m.shininess, mat)
        alpha_g = jnp.square(_gather(m.roughness, mat))
        spec_params = (ks, shin, alpha_g)
    if effects.normal_map:
        # Stored as arrays (``materialize_all`` takes them); the lobes read its components.
        n, length = materialize_all(*_normal_map(points, scene, effects))
        if effects.toksvig and effects.specular:
            spec_params = (ks, brdf.toksvig_shininess(shin, length[:, 0]),
                           brdf.toksvig_roughness(alpha_g, length[:, 0]))
    # From here on every vector is a tuple of per-point components (``vec.components``).
    n, albedo = components(n), components(albedo)
    frame = PointFrame(components(points.normal), components(points.view), mat, points.valid)
    incoming = _incoming(points, scene, effects)
    halves = _half_vectors(frame, incoming, n) if effects.specular else None
    if effects.shader_cost == 0:
        terms = _light_terms(frame, scene, effects, n, spec_params, incoming, halves)
    else:
        terms, (incoming, halves, albedo, spec_params, frame) = _layered_terms(
            points, scene, effects, n, spec_params, incoming, halves, albedo, frame)
    direct = _lit(terms, frame, scene, effects, albedo, spec_params, incoming, halves)
    rgb = [d + a * scene.lights.ambient[c] for c, (d, a) in enumerate(zip(direct, albedo))]
    if effects.emissive:
        rgb = [x + e for x, e in zip(rgb, components(_gather(m.emissive, mat)))]
    rgb = [jnp.where(points.valid, jnp.where(jnp.isfinite(x), x, 0.0), 0.0) for x in rgb]
    return stack(tuple(rgb))
