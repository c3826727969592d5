"""Directional shadow map: an orthographic depth pass from the first directional light, drawn
with the shared rasterizer (``rasterize_depth_clip`` on our own clip coordinates), and its lookup."""

from __future__ import annotations

import dataclasses
from functools import partial

import jax
import jax.numpy as jnp

from jaxrender.fusion import sum_small
from jaxrender.raster.rasterize import rasterize_depth_clip
from jaxrender.scene.scene import Scene, ShadowMap
from jaxrender.shading.vec import cross, safe_normalize
from jaxrender.types import Array


def light_frame(scene: Scene) -> tuple[Array, Array, Array]:
    """(origin [3], basis [3, 3] rows right, up, to_light, half_extent [3]) of a box around
    the scene's bounds seen from the first directional light."""
    lo, hi = scene.bounds[0], scene.bounds[1]
    origin = 0.5 * (lo + hi)
    radius = jnp.maximum(0.5 * jnp.linalg.norm(hi - lo), 1e-3) * 1.02
    back = scene.lights.dir_to_light[0]
    helper = jnp.where(jnp.abs(back[1]) < 0.99, jnp.asarray([0.0, 1.0, 0.0]),
                       jnp.asarray([1.0, 0.0, 0.0]))
    right = safe_normalize(cross(helper, back), jnp.asarray([1.0, 0.0, 0.0]))
    up = cross(back, right)
    basis = jnp.stack([right, up, back])
    return origin, basis, jnp.full((3,), radius)


def _light_space(points: Array, sm_origin, basis, half) -> Array:
    d = points - sm_origin[None, :]
    return sum_small(d[:, None, :] * basis[None, :, :]) / half[None, :]  # [N, 3] in [-1, 1]


@partial(jax.jit, static_argnames="size")
@jax.named_scope("shadow_pass")
def render_shadow_map(scene: Scene, size: int) -> ShadowMap:
    """One compiled program (light frame, transform, raster): done op by op it compiles dozens
    of small programs besides the rasterizer's, seconds of a scene's load."""
    if scene.lights.dir_to_light.shape[0] == 0:
        raise ValueError(f"scene {scene.name!r}: shadows need a directional light")
    origin, basis, half = light_frame(scene)
    q = _light_space(scene.positions, origin, basis, half)
    clip = jnp.concatenate([q[:, :2], -q[:, 2:3], jnp.ones_like(q[:, :1])], axis=-1)
    vis = rasterize_depth_clip(clip, scene.faces, size, size)
    return ShadowMap(depth=vis.depth, origin=origin, basis=basis, half_extent=half)


def with_shadow_map(scene: Scene) -> Scene:
    """The scene with its shadow map rendered (at ``effects.shadow_map_size``)."""
    return dataclasses.replace(scene, shadow=render_shadow_map(scene, scene.effects.shadow_map_size))


@jax.named_scope("shadow_lookup")
def shadow_factor(sm: ShadowMap, position: Array, normal: Array, bias: float) -> Array:
    """Fraction of the first directional light reaching each point, float32[N, 1], by 2x2
    percentage-closer filtering. The point is pushed 1.5 texels along its geometric normal
    (normal offset) and compared with a constant depth ``bias``; points outside the map are lit."""
    size = sm.depth.shape[-1]
    texel = 2.0 * sm.half_extent[0] / size
    q = _light_space(position + normal * (1.5 * texel), sm.origin, sm.basis, sm.half_extent)
    depth = 0.5 - 0.5 * q[:, 2]
    tx = (q[:, 0] * 0.5 + 0.5) * size - 0.5
    ty = (0.5 - q[:, 1] * 0.5) * size - 0.5
    x0f, y0f = jnp.floor(tx), jnp.floor(ty)
    fx, fy = tx - x0f, ty - y0f
    x0 = jnp.clip(x0f, -1, size).astype(jnp.int32)
    y0 = jnp.clip(y0f, -1, size).astype(jnp.int32)
    flat = sm.depth.reshape(-1)

    def lit(y, x):
        inside = (x >= 0) & (x < size) & (y >= 0) & (y < size)
        d = flat[jnp.clip(y, 0, size - 1) * size + jnp.clip(x, 0, size - 1)]
        return jnp.where(inside, (depth - bias <= d).astype(jnp.float32), 1.0)

    f = ((1 - fy) * ((1 - fx) * lit(y0, x0) + fx * lit(y0, x0 + 1))
         + fy * ((1 - fx) * lit(y0 + 1, x0) + fx * lit(y0 + 1, x0 + 1)))
    return f[:, None]
