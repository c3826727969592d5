"""Texture-aligned deferred shading (TADS, Timothy Lottes 2012): shading aligned to the texels
of the surface, filtered after shading, in one geometry pass (and, on a scene with blended
surfaces, the forward transparent pass after it).

  object_space's charts and sheets of the objects with a face that does not blend, packed in
  one virtual texture (tads_layout, ``prepare``)
  -> geometry pass: the G-buffer of physical positions and footprint gradients (tads_samples)
  -> find unique samples: each pixel's 1-4 bilinear texels (4 per anisotropic tap), minus those
     of its N, NW and W neighbours: a mask per pixel
  -> the masked (pixel, tap) pairs compacted and shaded through the chunked dispatch at each
     texel's own surface point (``object_space.shadel_points``), into the shade texture
  -> filtering: every covered pixel samples the shade texture bilinearly at its physical
     position (``aniso_taps`` taps along the gradient)
  -> blended surfaces, on a scene with them: the forward transparent pass over the filtered
     image, as deferred's (``transparency.transparent_pass``; its settings from
     ``BlendingConfig``). Blended faces are never shaded into the shade texture, so an object
     whose faces all blend has no chart and no texel (``os_sheet.build_sheet(opaque_only)``).

State: the shade texture float32[texels, 3] and the frame each texel was last shaded
int32[texels] (-1 never). With ``shade_every = N`` a texel is shaded when it was never shaded
or when its 8x8 tile is due: tile (cx, cy) of a sheet level is due on the frames t with
(cx + cy) % N == t % N; the other texels keep their value. The filter then weights a tap of
age a = t - frame by 1 / (1 + staleness * a) and renormalises the pixel's weights, so a stale
tap counts less than a fresh one beside it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.gbuffer import DEPTH_BYTES
from jaxrender.pipelines.object_space import ObjectSpaceConfig, shadel_points
from jaxrender.pipelines.os_sheet import LANES
from jaxrender.pipelines.registry import REGISTRY, register
from jaxrender.pipelines.tads_layout import TadsStatic, build_static
from jaxrender.pipelines.tads_samples import (Samples, decode, footprint_texels,
                                              gbuffer_channels, geometry_pass, sample_mask,
                                              unique_samples)
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.transparency import merge_counts, transparent_pass
from jaxrender.pipelines.visibility import visibility
from jaxrender.pipelines.waves import check_wave_size, count_waves
from jaxrender.shading import shade
from jaxrender.types import Array, Frame, pytree_dataclass

EPS = 1.0  # barycentric clamp of texels outside their owner triangle (Oxide's, object_space's)
TEXEL_BYTES = 12  # float32 RGB per texel of the shade texture
COUNTER_BYTES = 4  # int32 frame counter per texel
MAX_ANISO_TAPS = 7  # 4 texels a tap: the mask of 28 bits fits an int32


@dataclass(frozen=True)
class TadsConfig(BlendingConfig):
    """aniso_taps: bilinear taps along the footprint's gradient (1 = isotropic bilinear at the
    LOD of the longer footprint axis). shade_every: re-shade each 8x8 tile every N-th frame in
    sequences (texels never shaded are shaded at once). staleness: how much a tap's weight
    falls per frame of age, 1 / (1 + staleness * age) (refused with shade_every = 1, where no
    tap is ever stale). sheet_resolution, texel_density: the objects' sheets, as object_space
    (texel_density is refused with sheet_resolution > 0). wave_size: lanes per wave; pixels
    are grouped into waves by how many texels they shade (1, 2, 3, 4, ...), as the design does.
    """

    aniso_taps: int = 1
    shade_every: int = 1
    staleness: float = 1.0
    sheet_resolution: int = 0
    texel_density: float = 128.0
    wave_size: int = 32

    def __post_init__(self):
        super().__post_init__()
        checks = {"aniso_taps": 1 <= self.aniso_taps <= MAX_ANISO_TAPS,
                  "shade_every": self.shade_every >= 1, "staleness": self.staleness >= 0.0,
                  "sheet_resolution": 0 <= self.sheet_resolution <= self.max_sheet_resolution,
                  "texel_density": self.texel_density > 0}
        for k, ok in checks.items():
            if not ok:
                raise ValueError(f"tads: invalid {k} = {getattr(self, k)!r}")
        check_wave_size(self.wave_size)
        cls = type(self)
        if self.shade_every == 1 and self.staleness != cls.staleness:
            raise ValueError(f"tads: staleness = {self.staleness!r} has no effect with "
                             f"shade_every = 1 (every tap is fresh); set shade_every > 1")
        if self.sheet_resolution > 0 and self.texel_density != cls.texel_density:
            raise ValueError(f"tads: texel_density = {self.texel_density!r} has no effect with "
                             f"sheet_resolution = {self.sheet_resolution} > 0")

    # The sheet settings tads does not expose, at object_space's defaults (build_sheet reads
    # them from the config).
    max_sheet_resolution = ObjectSpaceConfig.max_sheet_resolution
    xatlas_resolution = ObjectSpaceConfig.xatlas_resolution
    force_xatlas = ObjectSpaceConfig.force_xatlas

    @property
    def taps_per_pixel(self) -> int:
        return 4 * int(self.aniso_taps)


@pytree_dataclass
class ShadeTexture:
    """The shade texture carried between frames: colour float32[texels, 3] and the frame each
    texel was last shaded, frame int32[texels] (-1 never)."""

    colour: Array
    frame: Array


def prepare(scene, cfg: TadsConfig) -> TadsStatic:
    """Charts, sheets and the virtual texture of ``scene`` (host); refuses unusable charts."""
    return build_static(scene, cfg)


def init(scene, static: TadsStatic, camera, cfg: TadsConfig) -> ShadeTexture:
    n = static.sheet.n_chunks * LANES
    return ShadeTexture(jnp.zeros((n, 3), jnp.float32), jnp.full((n,), -1, jnp.int32))


def due_texels(texel: Array, state: ShadeTexture, static: TadsStatic, t: Array,
               shade_every: int) -> Array:
    """bool[P, K]: texels to shade this frame (never shaded, or their tile is due)."""
    live = texel >= 0
    if shade_every == 1:
        return live
    sheet = static.sheet
    v = jnp.maximum(texel, 0) // LANES
    tile_due = (sheet.chunk_cx[v] + sheet.chunk_cy[v]) % shade_every == t % shade_every
    return live & (tile_due | (state.frame[jnp.maximum(texel, 0)] < 0))


def shade_texels(scene, camera, static: TadsStatic, smp: Samples, state: ShadeTexture, t,
                 cfg: TadsConfig) -> tuple[ShadeTexture, dispatch.WorkList]:
    """Shade the masked (pixel, tap) pairs, compacted, into their texels."""
    work = dispatch.WorkList.of(smp.shade.reshape(-1))
    texel = smp.texel.reshape(-1)
    identity = jnp.arange(static.sheet.n_chunks, dtype=jnp.int32)

    def lanes(lane, live):
        tex = texel[work.items[jnp.minimum(lane, work.items.shape[0] - 1)]]
        pts = shadel_points(scene, camera, static.sheet, identity, jnp.maximum(tex, 0), EPS)
        pts = dataclasses.replace(pts, valid=pts.valid & live)
        return tex, shade(pts, scene), live

    chunk = dispatch.resolve_chunk(cfg.chunk, cfg.width * cfg.height)
    colour, lanes_run = dispatch.dispatch_lanes(work.count, lanes, state.colour, chunk,
                                                work.items.shape[0])
    n = state.frame.shape[0]
    frame = state.frame.at[jnp.where(smp.shade, smp.texel, n).reshape(-1)].set(
        jnp.asarray(t, jnp.int32), mode="drop")
    return ShadeTexture(colour, frame), lanes_run


class Filtered(NamedTuple):
    image: Array
    missing: Array  # taps reading a texel never shaded
    stale: Array  # taps reading a texel shaded in an earlier frame
    overflow: Array


def filter_pass(tex: ShadeTexture, smp: Samples, t, cfg: TadsConfig, vis_overflow) -> Filtered:
    """Each pixel's weighted read of the shade texture; stale taps down-weighted."""
    use = smp.weight > 0.0
    addr = jnp.maximum(smp.texel, 0)
    shaded_at = tex.frame[addr]
    weight = smp.weight
    if cfg.shade_every > 1:
        age = jnp.maximum(jnp.asarray(t, jnp.int32) - shaded_at, 0).astype(jnp.float32)
        weight = weight / (1.0 + jnp.float32(cfg.staleness) * age)
        total = jnp.sum(weight, axis=1, keepdims=True)
        weight = jnp.where(total > 0.0, weight / jnp.where(total > 0.0, total, 1.0), 0.0)
    image = tex.colour[addr[:, 0]] * weight[:, 0, None]
    for k in range(1, addr.shape[1]):  # tap by tap: no [P, K, 3] intermediate
        image = image + tex.colour[addr[:, k]] * weight[:, k, None]
    image = image.reshape(cfg.height, cfg.width, 3)
    missing = jnp.sum(use & (shaded_at < 0), dtype=jnp.int32)
    stale = jnp.sum(use & (shaded_at >= 0) & (shaded_at < t), dtype=jnp.int32)
    overflow = vis_overflow + (missing > 0).astype(jnp.int32)
    return Filtered(poison_on_overflow(image, overflow), missing, stale, overflow)


@register("tads", TadsConfig, init=init, prepare=prepare)
def step(scene, static: TadsStatic, state: ShadeTexture, camera, t, cfg: TadsConfig):
    """Texture-aligned deferred shading: unique texels of the pixels' footprints shaded, then
    filtered; blended surfaces then composited over the opaque image by the forward
    transparent pass the other deferred pipelines run (``transparency.transparent_pass``)."""
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg)
    with jax.named_scope("geometry_pass"):
        gbuf = geometry_pass(scene, static, vis, cfg.aniso_taps)
    with jax.named_scope("find_unique_samples"):
        fp = decode(gbuf, static, cfg.aniso_taps)
        texel, weight, lod = footprint_texels(fp, static, cfg.aniso_taps)
        due = due_texels(texel, state, static, t, cfg.shade_every)
        smp = unique_samples(texel, weight, lod, due, cfg.height, cfg.width)
    with jax.named_scope("shade"):
        tex, work = shade_texels(scene, camera, static, smp, state, t, cfg)
    with jax.named_scope("filter"):
        out = filter_pass(tex, smp, t, cfg, vis.counts["overflow"])
    image, blended = transparent_pass(scene, camera, out.image, vis.depth, cfg)
    with jax.named_scope("counts"):
        counts, aux = tads_counts(static, cfg, fp, smp, due, work, out, vis)
        counts.update(vertex_counts(scene, full_passes=1))  # the raster pass
        counts = merge_counts(counts, blended)
    return Frame(poison_on_overflow(image, counts["overflow"]), counts, aux), tex


def tads_counts(static: TadsStatic, cfg: TadsConfig, fp, smp: Samples, due, work, out, vis):
    """Counts and per-pixel maps read off the samples and the shading work."""
    h, w, k = cfg.height, cfg.width, cfg.taps_per_pixel
    n_tex = static.sheet.n_chunks * LANES
    hits = jnp.zeros((n_tex,), jnp.int32).at[
        jnp.where(smp.shade, smp.texel, n_tex).reshape(-1)].add(1, mode="drop")
    unique = jnp.sum(hits > 0, dtype=jnp.int32)
    inv = work.invocations
    per_pixel = jnp.sum(smp.shade, axis=1, dtype=jnp.int32)
    in_footprint = jnp.sum(smp.distinct, axis=1, dtype=jnp.int32)
    classes = jnp.arange(1, k + 1, dtype=jnp.int32)
    shading_n = jnp.sum(per_pixel[None, :] == classes[:, None], axis=1, dtype=jnp.int32)
    footprint_n = jnp.sum(in_footprint[None, :] == classes[:, None], axis=1, dtype=jnp.int32)
    waves, util = count_waves(shading_n * classes, cfg.wave_size, inv)
    covered = jnp.sum(fp.covered, dtype=jnp.int32)
    gbuffer_bytes = covered * (gbuffer_channels(cfg.aniso_taps) * 4 + DEPTH_BYTES)
    taps_read = jnp.sum(smp.weight > 0.0, dtype=jnp.int32)
    repeated = smp.shade & (hits[jnp.maximum(smp.texel, 0)] > 1)
    hist = {f"pixels_shading_{c}": shading_n[c - 1] for c in range(1, k + 1)}
    hist.update({f"footprint_{c}_texels": footprint_n[c - 1] for c in range(1, k + 1)})
    counts = make_counts(
        shade_invocations=inv, covered_pixels=covered, waves=waves, lane_utilization=util,
        bytes_intermediate=gbuffer_bytes + (inv + taps_read) * TEXEL_BYTES,
        texels_shaded=unique,
        pixels_shading_0=jnp.sum(fp.covered & (per_pixel == 0), dtype=jnp.int32),
        duplicates_removed=jnp.sum(smp.distinct & smp.claimed & due, dtype=jnp.int32),
        duplicates_missed=inv - unique,
        gbuffer_bytes=gbuffer_bytes,
        # float: a scene's charts can need more than 2^31 bytes (thin at 1920x1080: 2.4 GB).
        # Without the spare chunk of a scene whose faces all blend: no object's texels.
        shade_texture_bytes=jnp.float32((n_tex - static.sheet.spare_chunks * LANES)
                                        * (TEXEL_BYTES + COUNTER_BYTES)),
        taps_read=taps_read, stale_taps=out.stale, missing_taps=out.missing,
        alpha_invocations=vis.counts["alpha_invocations"], overflow=out.overflow, **hist)
    aux = {"sample_class": jnp.where(fp.covered, per_pixel, -1).reshape(h, w),
           "sample_mask": sample_mask(smp.shade).reshape(h, w),
           "footprint_texels": jnp.where(fp.covered, in_footprint, 0).reshape(h, w),
           "duplicates": jnp.sum(repeated, axis=1, dtype=jnp.int32).reshape(h, w),
           "mip_level": smp.lod.reshape(h, w)}
    return counts, aux


render = REGISTRY["tads"].render
render_sequence = REGISTRY["tads"].render_sequence

__all__ = ["ShadeTexture", "TadsConfig", "due_texels", "filter_pass", "init", "prepare",
           "render", "render_sequence", "shade_texels", "step", "tads_counts"]
