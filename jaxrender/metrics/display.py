"""Display handling in one place: linear radiance -> what a metric compares.

Pipelines produce linear RGB. The LDR metrics (and the published DACS numbers) compare
display-referred images: scale by the exposure, clamp to [0, 1], then sRGB-encode (IEC 61966-2-1).
HDR comparisons keep linear values (negative values clamped to 0) and leave tone mapping to the
metric that defines one (HDR-FLIP).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.shading.srgb import srgb_decode, srgb_encode

Array = jax.Array

__all__ = ["MODES", "srgb_decode", "srgb_encode", "to_display"]

MODES = ("ldr", "hdr")


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
