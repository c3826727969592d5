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
    """v / |v| of [..., 3] arrays, or ``fallback`` (broadcast to v's shape) where |v| is zero or
    not finite: ``normalize3`` of their components."""
    fallback = jnp.broadcast_to(fallback, v.shape)
    return stack(normalize3(components(v), components(fallback)))


def cross(a: Array, b: Array) -> Array:
    return jnp.cross(a, b)


# Vectors as tuples of per-point components (x, y, z), each float32[N] (or a scalar broadcast
# to it): arithmetic on them stays one value per point, so XLA can fuse a whole stage into one
# kernel. On [N, 3] arrays each colour channel's kernel recomputed the per-point terms it
# shares with the other two (the lobes, the cosines), and XLA stored those terms instead.


def components(v: Array) -> tuple[Array, ...]:
    """The columns of [N, C] (or the entries of [C]) as a tuple of C arrays."""
    return tuple(v[..., i] for i in range(v.shape[-1]))


def dot3(a: tuple, b: tuple) -> Array:
    """a . b of component tuples, added in component order (as ``dot``)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize3(v: tuple, fallback: tuple) -> tuple:
    """``safe_normalize`` of a component tuple: v / |v|, or ``fallback`` where |v| is zero or
    not finite."""
    n2 = dot3(v, v)
    ok = (n2 > TINY) & jnp.isfinite(n2)
    inv = jnp.where(ok, 1.0 / jnp.sqrt(jnp.where(ok, n2, 1.0)), 0.0)
    return tuple(jnp.where(ok, c * inv, f) for c, f in zip(v, fallback))


def cross3(a: tuple, b: tuple) -> tuple:
    """a x b of component tuples (as ``jnp.cross``)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def stack(v: tuple) -> Array:
    """A component tuple of float32[N] as one float32[N, C] array."""
    return jnp.stack(v, axis=-1)
