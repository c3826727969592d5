"""Texture-aligned deferred shading, steps 1 and 2: the geometry pass's modified G-buffer and
the find-unique-samples pass.

G-buffer (``TADS_LAYOUT``, float32 planes, the position's int32 stored bit-exactly): the
physical position (``tads_layout``: level-0 virtual texels, 8 sub-texel bits), the gradient
vector (the longer of the two screen-axis footprint vectors, in level-0 texels) and, with
anisotropic filtering, the footprint thickness (the shorter one's length). The pixel's normal
and tangent frame are not stored: the texels are shaded at their own surface points (from the
sheet's triangle-id map, as object_space does), so no pass here would read them.

Find unique samples: a pixel's filter footprint (``os_marking.taps`` in bilinear mode at the
LOD its gradient selects; ``aniso_taps`` bilinear taps along the gradient, the LOD raised to
the thickness for the low-pass across it) covers 1 to 4 texels per tap. The pixel drops texels
it already lists and every texel in the footprint of its north, north-west and west neighbour:
a neighbour (or, by induction along the scanline order, one of its own earlier neighbours)
shades those. What is left is the pixel's mask (bit k: tap k's texel is shaded by this pixel).
Texels shared by pixels that are not such neighbours are shaded more than once (the rule's
misses, counted by the pipeline).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.pipelines.os_marking import Footprint, footprint, taps
from jaxrender.pipelines.os_sheet import LANES
from jaxrender.pipelines.tads_layout import PAGE, SUBTEXEL, SUBTEXEL_BITS, TadsStatic
from jaxrender.types import Array


def tads_layout(aniso_taps: int) -> tuple[tuple[str, int], ...]:
    """(plane, channels) of the TADS G-buffer; the thickness only with anisotropic filtering."""
    planes = (("physical_position", 2), ("gradient", 2))
    return planes + ((("thickness", 1),) if aniso_taps > 1 else ())


def gbuffer_channels(aniso_taps: int) -> int:
    return sum(c for _, c in tads_layout(aniso_taps))


def geometry_pass(scene, static: TadsStatic, vis, aniso_taps: int) -> Array:
    """The G-buffer float32[P, C] of a single-sample visibility buffer (uncovered pixels: a
    physical position of -1)."""
    n = vis.tri_id.size
    flat = lambda a: a.reshape((n,) + a.shape[2:])  # noqa: E731
    fp = footprint(scene, static.sheet, flat(vis.tri_id), flat(vis.bary), flat(vis.dbary_dx),
                   flat(vis.dbary_dy))
    res = static.sheet.obj_res[fp.obj]
    rf = res.astype(jnp.float32)[:, None]
    # Kept inside the object's square, so that the page table finds the object again.
    local = jnp.clip(jnp.round(fp.st * rf * SUBTEXEL).astype(jnp.int32), 0,
                     res[:, None] * SUBTEXEL - 1)
    pos = local + static.origin[fp.obj] * SUBTEXEL
    pos = jnp.where(fp.covered[:, None], pos, -1)
    gx, gy = fp.dst_dx * rf, fp.dst_dy * rf
    lx, ly = jnp.linalg.norm(gx, axis=-1), jnp.linalg.norm(gy, axis=-1)
    grad = jnp.where((lx >= ly)[:, None], gx, gy)
    planes = [jax.lax.bitcast_convert_type(pos, jnp.float32),
              jnp.where(fp.covered[:, None], grad, 0.0)]
    if aniso_taps > 1:
        planes.append(jnp.where(fp.covered, jnp.minimum(lx, ly), 0.0)[:, None])
    return jnp.concatenate(planes, axis=-1)


def decode(gbuf: Array, static: TadsStatic, aniso_taps: int) -> Footprint:
    """The filter footprint of each pixel from its G-buffer row alone: the page table gives the
    object under the physical position, the object's origin the chart point (exact: a power of
    two divides an integer of at most 22 bits)."""
    pos = jax.lax.bitcast_convert_type(gbuf[:, 0:2], jnp.int32)
    covered = pos[:, 0] >= 0
    texel = jnp.right_shift(jnp.maximum(pos, 0), SUBTEXEL_BITS) // PAGE
    obj = jnp.where(covered, static.page_object[texel[:, 1] * static.pages_wide + texel[:, 0]],
                    0)
    covered = covered & (obj >= 0)
    obj = jnp.maximum(obj, 0)
    # At least 1: an uncovered pixel's stand-in object 0 may have no sheet (res 0), and its
    # chart point, unused, should not be 0 / 0.
    rf = jnp.maximum(static.sheet.obj_res[obj], 1).astype(jnp.float32)[:, None]
    st = (pos - static.origin[obj] * SUBTEXEL).astype(jnp.float32) / (rf * SUBTEXEL)
    grad = gbuf[:, 2:4]
    if aniso_taps > 1:
        length = jnp.linalg.norm(grad, axis=-1, keepdims=True)
        unit = grad / jnp.maximum(length, 1e-30)
        across = jnp.stack([-unit[:, 1], unit[:, 0]], axis=-1) * gbuf[:, 4:5]
    else:
        across = jnp.zeros_like(grad)
    return Footprint(obj, st, grad / rf, across / rf, covered)


class Samples(NamedTuple):
    """Per pixel P and tap texel K: texel int32[P, K] (virtual texel id, -1 none), weight
    float32[P, K], distinct bool[P, K] (first occurrence in the pixel), claimed bool[P, K]
    (in the N, NW or W neighbour's footprint), shade bool[P, K] (this pixel shades it),
    lod float32[P]."""

    texel: Array
    weight: Array
    distinct: Array
    claimed: Array
    shade: Array
    lod: Array


def footprint_texels(fp: Footprint, static: TadsStatic, aniso_taps: int):
    """(texel int32[P, K], weight float32[P, K], lod float32[P]): the bilinear taps of every
    pixel at its LOD, K = 4 * aniso_taps."""
    t = taps(fp, static.sheet, jnp.float32(0.0), "bilinear", aniso_taps)
    return jnp.where(t.weight > 0.0, t.chunk * LANES + t.lane, -1), t.weight, t.lod


def neighbour_claims(texel: Array, height: int, width: int) -> Array:
    """bool[P, K]: the texel is also in the footprint of the pixel's north, north-west or west
    neighbour (pixels outside the image have none)."""
    k = texel.shape[1]
    grid = jnp.pad(texel.reshape(height, width, k), ((1, 0), (1, 0), (0, 0)),
                   constant_values=-1)
    nbrs = jnp.concatenate([grid[:-1, 1:], grid[:-1, :-1], grid[1:, :-1]], axis=-1)
    nbrs = nbrs.reshape(height * width, 3 * k)
    hit = jnp.zeros(texel.shape, bool)
    for j in range(3 * k):  # a loop over the few neighbour taps: no [P, K, 3K] intermediate
        hit = hit | (texel == nbrs[:, j:j + 1])
    return hit & (texel >= 0)


def first_occurrence(texel: Array) -> Array:
    """bool[P, K]: the tap's texel is listed for the first time in its pixel."""
    cols = [texel[:, 0] >= 0]
    for k in range(1, texel.shape[1]):
        seen = jnp.any(texel[:, :k] == texel[:, k:k + 1], axis=1)
        cols.append((texel[:, k] >= 0) & ~seen)
    return jnp.stack(cols, axis=1)


def unique_samples(texel: Array, weight: Array, lod: Array, due: Array, height: int,
                   width: int) -> Samples:
    """The neighbour rule over the texels that are ``due`` (bool[P, K]) to be shaded."""
    distinct = first_occurrence(texel)
    claimed = neighbour_claims(texel, height, width)
    return Samples(texel, weight, distinct, claimed, distinct & ~claimed & due, lod)


def sample_mask(shade: Array) -> Array:
    """int32[P]: bit k set when the pixel shades tap k's texel."""
    bits = jnp.left_shift(jnp.int32(1), jnp.arange(shade.shape[1], dtype=jnp.int32))
    return jnp.sum(jnp.where(shade, bits[None, :], 0), axis=1, dtype=jnp.int32)


__all__ = ["Samples", "decode", "first_occurrence", "footprint_texels", "gbuffer_channels",
           "geometry_pass", "neighbour_claims", "sample_mask", "tads_layout", "unique_samples"]
