"""Small vector helpers that keep every value finite (zero-length inputs get a fallback)."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.fusion import sum_small
from jaxrender.types import Array

TINY = 1e-30


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis, keeping it: [..., 3] x [..., 3] -> [..., 1]."""
    return sum_small(a * b, axis=-1, keepdims=True)


def safe_normalize(v: Array, fallback: Array) -> Array:
    """v / |v|, or ``fallback`` (same shape) where |v| is zero or not finite."""
    n2 = dot(v, v)
    ok = (n2 > TINY) & jnp.isfinite(n2)
    return jnp.where(ok, v * jnp.where(ok, 1.0 / jnp.sqrt(jnp.where(ok, n2, 1.0)), 0.0), fallback)


def cross(a: Array, b: Array) -> Array:
    return jnp.cross(a, b)
