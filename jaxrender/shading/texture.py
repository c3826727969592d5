"""Texture filtering from the packed MIP atlas (see jaxrender.scene.textures): LOD from the uv
derivatives, bilinear per level, trilinear between levels, an anisotropic option."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.fusion import sum_small
from jaxrender.scene.textures import Textures
from jaxrender.types import Array


def footprint(duv_dx: Array, duv_dy: Array, resolution: int) -> tuple[Array, Array]:
    """Lengths in level-0 texels of the pixel's footprint axes: (|duv/dx| R, |duv/dy| R), [N]."""
    r = jnp.float32(resolution)
    lx = jnp.sqrt(sum_small(jnp.square(duv_dx * r)))
    ly = jnp.sqrt(sum_small(jnp.square(duv_dy * r)))
    return lx, ly


def lod_isotropic(duv_dx: Array, duv_dy: Array, resolution: int) -> Array:
    """The GL LOD: log2 of the longer footprint axis in texels (unclamped, finite), [N]."""
    lx, ly = footprint(duv_dx, duv_dy, resolution)
    return jnp.log2(jnp.maximum(jnp.maximum(lx, ly), 1e-20))


def bilinear_level(tex: Textures, tex_id: Array, uv: Array, level: Array) -> Array:
    """Bilinear sample (wrap) of integer MIP ``level`` int32[N] of textures ``tex_id`` -> [N, 4]."""
    r = tex.resolution
    rows = 2 * r - 1
    flat = tex.atlas.reshape(-1, 4)
    size = jnp.right_shift(jnp.int32(r), level)
    sf = size.astype(jnp.float32)
    tx = uv[:, 0] * sf - 0.5
    ty = (1.0 - uv[:, 1]) * sf - 0.5
    x0f, y0f = jnp.floor(tx), jnp.floor(ty)
    fx, fy = (tx - x0f)[:, None], (ty - y0f)[:, None]
    # Wrapped before the int cast so huge uvs (stripes to the horizon) stay exact. Sizes are
    # powers of two: the wrap is a multiply, a floor and a mask, each exact, where jnp.mod
    # would run a float remainder and an integer division per texel.
    inv = 1.0 / sf
    x0 = (x0f - jnp.floor(x0f * inv) * sf).astype(jnp.int32)
    y0 = (y0f - jnp.floor(y0f * inv) * sf).astype(jnp.int32)
    x1 = (x0 + 1) & (size - 1)
    y1 = (y0 + 1) & (size - 1)
    base = (tex_id * rows + (2 * r - 2 * size)) * r

    def at(y, x):
        return flat[base + y * r + x]

    return ((1.0 - fy) * ((1.0 - fx) * at(y0, x0) + fx * at(y0, x1))
            + fy * ((1.0 - fx) * at(y1, x0) + fx * at(y1, x1)))


def trilinear(tex: Textures, tex_id: Array, uv: Array, lod: Array) -> Array:
    """Trilinear sample at a fractional LOD float32[N] (clamped to the chain) -> [N, 4]."""
    top = tex.levels - 1
    lod = jnp.clip(jnp.where(jnp.isfinite(lod), lod, 0.0), 0.0, jnp.float32(top))
    l0 = jnp.floor(lod)
    t = (lod - l0)[:, None]
    i0 = l0.astype(jnp.int32)
    i1 = jnp.minimum(i0 + 1, top)
    return (1.0 - t) * bilinear_level(tex, tex_id, uv, i0) + t * bilinear_level(tex, tex_id, uv, i1)


@jax.named_scope("texture")
def sample(tex: Textures, tex_id: Array, uv: Array, duv_dx: Array, duv_dy: Array,
           aniso_taps: int = 1) -> Array:
    """Filtered texture lookup -> float32[N, 4].

    aniso_taps == 1: trilinear at the isotropic LOD. aniso_taps = n > 1: n trilinear taps spread
    evenly along the major footprint axis (at offsets ((i + 0.5) / n - 0.5) * major), each at
    LOD log2(max(minor, major / n)), averaged.
    """
    tex_id = jnp.clip(tex_id, 0, tex.atlas.shape[0] - 1)
    uv = jnp.where(jnp.isfinite(uv), uv, 0.0)
    if aniso_taps == 1:
        return trilinear(tex, tex_id, uv, lod_isotropic(duv_dx, duv_dy, tex.resolution))
    lx, ly = footprint(duv_dx, duv_dy, tex.resolution)
    x_major = (lx >= ly)[:, None]
    axis = jnp.where(x_major, duv_dx, duv_dy)
    major, minor = jnp.maximum(lx, ly), jnp.minimum(lx, ly)
    lod = jnp.log2(jnp.maximum(jnp.maximum(minor, major / aniso_taps), 1e-20))
    acc = jnp.zeros(uv.shape[:1] + (4,), jnp.float32)
    for i in range(aniso_taps):
        off = (i + 0.5) / aniso_taps - 0.5
        acc = acc + trilinear(tex, tex_id, uv + axis * off, lod)
    return acc / aniso_taps
