"""The G-buffer: the surface attributes a deferred attribute pass writes per pixel (sample), as
float32 channels in one array a field, and the lighting pass's way back from them to surface points.

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


def gbuffer_fields(pts: SurfacePoints) -> tuple[Array, ...]:
    """SurfacePoints [N] -> the GBUFFER_LAYOUT fields, float32[N, channels] each (material
    ids bit for bit).

    The G-buffer is stored as one array a field (a render target each, as engines bind them),
    not as rows of all the channels: concatenating the fields into rows was one XLA kernel that
    took 1.7x as long as writing the fields apart (RESULTS.md, twenty-fifth session)."""
    cols = []
    for name, _ in GBUFFER_LAYOUT:
        v = getattr(pts, name)
        if name == "material":
            v = jax.lax.bitcast_convert_type(v.astype(jnp.int32), jnp.float32)[:, None]
        cols.append(v)
    return tuple(cols)


def empty_gbuffer(n: int) -> tuple[Array, ...]:
    """A G-buffer of ``n`` entries, zeros: float32[n, channels] for each field."""
    return tuple(jnp.zeros((n, c), jnp.float32) for _, c in GBUFFER_LAYOUT)


def gbuffer_entries(gbuf: tuple[Array, ...], items: Array) -> tuple[Array, ...]:
    """The G-buffer's entries ``items`` int32[N], field by field."""
    return tuple(f[items] for f in gbuf)


def unpack_gbuffer(gbuf: tuple[Array, ...], camera, live: Array) -> SurfacePoints:
    """G-buffer fields [N, channels] (GBUFFER_LAYOUT order) -> SurfacePoints seen from
    ``camera``; ``live`` bool[N] marks the entries that hold a surface."""
    fields = {name: f for (name, _), f in zip(GBUFFER_LAYOUT, gbuf, strict=True)}
    mat = jax.lax.bitcast_convert_type(fields.pop("material")[:, 0], jnp.int32)
    pos = fields["position"]
    view = safe_normalize(camera.eye[None, :] - pos, fields["normal"])
    return SurfacePoints(view=view, material=mat, tri_id=jnp.where(live, 0, -1), valid=live,
                         **fields)


def shade_through(pts: SurfacePoints, scene, camera, live: Array) -> Array:
    """``shade`` by the deferred lighting pass's path: points -> G-buffer channels -> points.
    The barrier keeps the channels materialised, as deferred's planes are, so that the compiler
    cannot fuse attribute and lighting math differently from deferred."""
    fields = jax.lax.optimization_barrier(gbuffer_fields(pts))
    return shade(unpack_gbuffer(fields, camera, live), scene)
