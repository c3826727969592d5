"""Display handling in one place: linear radiance -> what a metric compares.

Pipelines produce linear RGB. The LDR metrics (and the published DACS numbers) compare
display-referred images: scale by the exposure, clamp to [0, 1], then sRGB-encode (IEC 61966-2-1).
HDR comparisons keep linear values (negative values clamped to 0) and leave tone mapping to the
metric that defines one (HDR-FLIP).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

Array = jax.Array

# IEC 61966-2-1 sRGB transfer function constants.
SRGB_LINEAR_CUTOFF = 0.0031308  # linear value where the curve changes branch
SRGB_ENCODED_CUTOFF = 0.04045  # encoded value of the same point
SRGB_SLOPE = 12.92
SRGB_SCALE = 1.055
SRGB_OFFSET = 0.055
SRGB_GAMMA = 2.4

MODES = ("ldr", "hdr")


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


def to_display(linear: Array, mode: str = "ldr", exposure: float = 0.0) -> Array:
    """Linear RGB -> the image a metric compares.

    mode="ldr": ``srgb_encode(clip(linear * 2**exposure, 0, 1))`` (display-referred, default).
    mode="hdr": ``max(linear * 2**exposure, 0)`` (scene-referred linear, for HDR-FLIP or an
    HDR ``data_range``).
    """
    if mode not in MODES:
        raise ValueError(f"to_display: mode must be one of {MODES}, got {mode!r}")
    x = jnp.asarray(linear)
    if exposure != 0.0:
        x = x * (2.0**exposure)
    if mode == "hdr":
        return jnp.maximum(x, 0.0)
    return srgb_encode(jnp.clip(x, 0.0, 1.0))
