"""The sRGB transfer function (IEC 61966-2-1): linear [0, 1] <-> encoded [0, 1]. Used by the
pipelines that compare colours as displayed (DACS, checkerboard) and by the display-referred
metrics."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.types import Array

# IEC 61966-2-1 sRGB transfer function constants.
SRGB_LINEAR_CUTOFF = 0.0031308  # linear value where the curve changes branch
SRGB_ENCODED_CUTOFF = 0.04045  # encoded value of the same point
SRGB_SLOPE = 12.92
SRGB_SCALE = 1.055
SRGB_OFFSET = 0.055
SRGB_GAMMA = 2.4


def srgb_encode(linear: Array) -> Array:
    """Linear [0, 1] -> sRGB-encoded [0, 1]. Inputs outside [0, 1] must be clamped first."""
    safe = jnp.maximum(linear, SRGB_LINEAR_CUTOFF)  # keep the power branch away from 0
    curve = SRGB_SCALE * jnp.power(safe, 1.0 / SRGB_GAMMA) - SRGB_OFFSET
    return jnp.where(linear <= SRGB_LINEAR_CUTOFF, SRGB_SLOPE * linear, curve)


def srgb_decode(encoded: Array) -> Array:
    """sRGB-encoded [0, 1] -> linear [0, 1]."""
    safe = jnp.maximum(encoded, SRGB_ENCODED_CUTOFF)
    curve = jnp.power((safe + SRGB_OFFSET) / SRGB_SCALE, SRGB_GAMMA)
    return jnp.where(encoded <= SRGB_ENCODED_CUTOFF, encoded / SRGB_SLOPE, curve)
