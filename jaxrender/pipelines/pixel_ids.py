"""Small per-pixel helpers shared by the checkerboard and DACS pipelines: surface ids of a
visibility pass, neighbour fetches that know the image border, luma, and LOD-biased points.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxrender.shading.srgb import srgb_encode
from jaxrender.types import Array, SurfacePoints

ID_KINDS = ("triangle", "object", "material", "none")
LUMAS = {"simple": (0.25, 0.5, 0.25), "rec709": (0.2126, 0.7152, 0.0722)}
SPACES = ("display", "linear")


def check_choice(name: str, value, allowed) -> None:
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(map(str, allowed))}; got {value!r}")


def surface_ids(scene, tri: Array, kind: str) -> Array:
    """int32 id per pixel of ``kind`` (triangle, object or material; -1 where uncovered).
    ``none`` gives 0 on covered pixels and -1 elsewhere (only coverage separates surfaces)."""
    covered = tri >= 0
    t = jnp.maximum(tri, 0)
    if kind == "triangle":
        ids = tri
    elif kind == "object":
        ids = scene.tri_object[t]
    elif kind == "material":
        ids = scene.tri_material[t]
    else:
        ids = jnp.zeros_like(tri)
    return jnp.where(covered, ids.astype(jnp.int32), -1)


def inside(h: int, w: int, dy: int, dx: int) -> np.ndarray:
    """bool[h, w] (static): the pixel (y + dy, x + dx) lies in the image."""
    y = np.arange(h)[:, None] + dy
    x = np.arange(w)[None, :] + dx
    return (y >= 0) & (y < h) & (x >= 0) & (x < w)


def shift(a: Array, dy: int, dx: int, fill=0) -> Array:
    """b[y, x] = a[y + dy, x + dx] where that is inside the image, else ``fill`` (static
    offsets; trailing channel axes allowed)."""
    h, w = a.shape[0], a.shape[1]
    pad = [(max(-dy, 0), max(dy, 0)), (max(-dx, 0), max(dx, 0))] + [(0, 0)] * (a.ndim - 2)
    p = jnp.pad(a, pad, constant_values=fill)
    ys, xs = max(dy, 0), max(dx, 0)  # = offset + top/left padding
    return p[ys:ys + h, xs:xs + w]


def luma(rgb: Array, kind: str = "simple", space: str = "display") -> Array:
    """Luma of linear RGB (..., 3): 0.25R + 0.5G + 0.25B (``simple``) or Rec. 709 weights, of
    the display-referred (clamped, sRGB-encoded) or the linear colour."""
    c = rgb
    if space == "display":
        c = srgb_encode(jnp.clip(rgb, 0.0, 1.0))
    wts = LUMAS[kind]
    return c[..., 0] * wts[0] + c[..., 1] * wts[1] + c[..., 2] * wts[2]


def lod_scaled(points: SurfacePoints, scale_x: float, scale_y: float) -> SurfacePoints:
    """Points whose uv derivatives are scaled (texture LOD bias b: scale 2**b; a half-width
    target: x footprint 2)."""
    if scale_x == 1.0 and scale_y == 1.0:
        return points
    return dataclasses.replace(points, duv_dx=points.duv_dx * jnp.float32(scale_x),
                               duv_dy=points.duv_dy * jnp.float32(scale_y))
