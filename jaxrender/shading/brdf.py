"""BRDF lobes. All are elementwise: they take the cosines and per-point parameters (float32[N]
arrays or scalars; the shader passes one colour channel of ``ks`` at a time) and return values
of f(l, v) of their broadcast shape (the cosine factor is applied by the caller). Every lobe
is finite for any exponent or roughness, including grazing and back-facing directions."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.types import Array

INV_PI = 1.0 / jnp.pi


def lambert(albedo: Array) -> Array:
    return albedo * INV_PI


def blinn_phong(ks: Array, shininess: Array, n_dot_h: Array) -> Array:
    """Energy-normalised Blinn-Phong, ks (n + 8) / (8 pi) cos(theta_h)^n.

    The power is exp(n log(cos)) with cos clamped away from 0, so n = 1e6 gives 0 off the peak
    and (n + 8) / (8 pi) at it: finite, never inf * 0."""
    c = jnp.clip(n_dot_h, 1e-30, 1.0)
    n = jnp.maximum(shininess, 0.0)
    lobe = jnp.exp(n * jnp.log(c)) * jnp.where(n_dot_h > 0.0, 1.0, 0.0)
    return ks * ((n + 8.0) * (INV_PI / 8.0)) * lobe


def toksvig_shininess(shininess: Array, normal_length: Array) -> Array:
    """Toksvig (2005): s' = ft s with ft = |Na| / (|Na| + s (1 - |Na|)), |Na| the length of the
    filtered (shortened) normal-map normal in (0, 1]."""
    na = jnp.clip(normal_length, 1e-4, 1.0)
    return shininess * na / (na + shininess * (1.0 - na))


def toksvig_roughness(alpha: Array, normal_length: Array) -> Array:
    """The same idea for GGX: widen alpha^2 by the normal variance (1 - |Na|) / |Na|."""
    na = jnp.clip(normal_length, 1e-4, 1.0)
    return jnp.sqrt(jnp.minimum(jnp.square(alpha) + (1.0 - na) / na, 1.0))


def ggx(f0: Array, alpha: Array, n_dot_l: Array, n_dot_v: Array, n_dot_h: Array,
        v_dot_h: Array) -> Array:
    """Cook-Torrance with the GGX distribution, height-correlated Smith visibility and Schlick
    Fresnel. alpha = roughness^2."""
    return ggx_dv(alpha, n_dot_l, n_dot_v, n_dot_h) * schlick(f0, v_dot_h)


def ggx_dv(alpha: Array, n_dot_l: Array, n_dot_v: Array, n_dot_h: Array) -> Array:
    """``ggx`` without its Fresnel factor: the GGX distribution times the height-correlated
    Smith visibility, 0 where the light is below the surface."""
    a2 = jnp.square(jnp.maximum(alpha, 1e-3))
    nl = jnp.clip(n_dot_l, 0.0, 1.0)
    nv = jnp.clip(n_dot_v, 1e-4, 1.0)
    nh = jnp.clip(n_dot_h, 0.0, 1.0)
    denom = jnp.square(nh) * (a2 - 1.0) + 1.0
    d = a2 * INV_PI / jnp.square(jnp.maximum(denom, 1e-12))
    vis = 0.5 / jnp.maximum(nl * jnp.sqrt(nv * nv * (1.0 - a2) + a2)
                            + nv * jnp.sqrt(nl * nl * (1.0 - a2) + a2), 1e-12)
    return d * vis * jnp.where(n_dot_l > 0.0, 1.0, 0.0)


def schlick(f0: Array, v_dot_h: Array) -> Array:
    """Schlick's Fresnel approximation, f0 + (1 - f0) (1 - v.h)^5."""
    return f0 + (1.0 - f0) * jnp.power(1.0 - jnp.clip(v_dot_h, 0.0, 1.0), 5.0)
