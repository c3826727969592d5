"""The G-buffer: the surface attributes a deferred attribute pass writes per pixel (sample), as
float32 channels, and the lighting pass's way back from them to surface points.

Deferred writes full-screen planes of these channels; DACS and checkerboard shade through the
same packing on just the pixels they shade (``shade_through``), so that their shading is
deferred's, bit for bit.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.shading import shade
from jaxrender.shading.vec import safe_normalize
from jaxrender.types import Array, SurfacePoints

# (field, channels): the G-buffer planes, float32 each; material ids are stored bit-exactly.
GBUFFER_LAYOUT = (("position", 3), ("normal", 3), ("shading_normal", 3), ("tangent", 4),
                  ("uv", 2), ("duv_dx", 2), ("duv_dy", 2), ("material", 1))
GBUFFER_CHANNELS = sum(c for _, c in GBUFFER_LAYOUT)
PIXEL_BYTES = GBUFFER_CHANNELS * 4
DEPTH_BYTES = 4  # the depth buffer (D32F) written by the same pass


def gbuffer_fields(pts: SurfacePoints) -> list[Array]:
    """SurfacePoints [N] -> the GBUFFER_LAYOUT fields, float32[N, channels] each (material
    ids bit for bit)."""
    cols = []
    for name, _ in GBUFFER_LAYOUT:
        v = getattr(pts, name)
        if name == "material":
            v = jax.lax.bitcast_convert_type(v.astype(jnp.int32), jnp.float32)[:, None]
        cols.append(v)
    return cols


def pack_gbuffer(pts: SurfacePoints) -> Array:
    """SurfacePoints [N] -> float32[N, GBUFFER_CHANNELS] in GBUFFER_LAYOUT order."""
    return jnp.concatenate(gbuffer_fields(pts), axis=-1)


def unpack_gbuffer(rows: Array, camera, live: Array) -> SurfacePoints:
    """G-buffer rows [N, GBUFFER_CHANNELS] -> SurfacePoints seen from ``camera``; ``live``
    bool[N] marks the rows that hold a surface."""
    fields, at = {}, 0
    for name, c in GBUFFER_LAYOUT:
        fields[name] = rows[:, at:at + c]
        at += c
    mat = jax.lax.bitcast_convert_type(fields.pop("material")[:, 0], jnp.int32)
    pos = fields["position"]
    view = safe_normalize(camera.eye[None, :] - pos, fields["normal"])
    return SurfacePoints(view=view, material=mat, tri_id=jnp.where(live, 0, -1), valid=live,
                         **fields)


def shade_through(pts: SurfacePoints, scene, camera, live: Array) -> Array:
    """``shade`` by the deferred lighting pass's path: points -> G-buffer channels -> points.
    The barrier keeps the channels materialised, as deferred's planes are, so that the compiler
    cannot fuse attribute and lighting math differently from deferred."""
    rows = jax.lax.optimization_barrier(pack_gbuffer(pts))
    return shade(unpack_gbuffer(rows, camera, live), scene)
