"""Deferred shading: a G-buffer pass writes each visible surface's attributes, then a lighting
pass shades every covered pixel once from the G-buffer.

The G-buffer is real: the attribute pass writes the ``GBUFFER_LAYOUT`` channels of every covered
pixel (sample) into full-screen float32 planes through the chunked dispatch, and the lighting
pass reads them back and calls the shared ``shade``. The bytes written and read are the planes'
bytes times the pixels (samples) that the two work lists touched. Under MSAA the G-buffer holds
every sample; lighting shades one representative sample per pixel and, with
``per_sample_shading``, also every sample whose surface differs from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp

from jaxrender.pipelines.base import (PipelineConfig, dispatch_points, make_counts,
                                      poison_on_overflow, visibility)
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.raster import samples as sample_patterns
from jaxrender.shading import shade, surface_points
from jaxrender.shading.vec import safe_normalize
from jaxrender.types import Frame, SurfacePoints

# (field, channels): the G-buffer planes, float32 each; material ids are stored bit-exactly.
GBUFFER_LAYOUT = (("position", 3), ("normal", 3), ("shading_normal", 3), ("tangent", 4),
                  ("uv", 2), ("duv_dx", 2), ("duv_dy", 2), ("material", 1))
GBUFFER_CHANNELS = sum(c for _, c in GBUFFER_LAYOUT)
DEPTH_BYTES = 4  # the depth buffer (D32F) written by the same pass


@dataclass(frozen=True)
class DeferredConfig(PipelineConfig):
    """msaa: 1, 2, 4 or 8 samples; per_sample_shading: under MSAA, also shade the samples whose
    surface (triangle) differs from the pixel's representative sample (refused with msaa = 1,
    where there is one sample per pixel and it would do nothing). wave_size: lanes per wave of
    the lighting pass (8x8 tiles split into waves; a wave runs if any pixel is covered).
    """

    msaa: int = 1
    per_sample_shading: bool = False
    wave_size: int = 32

    def __post_init__(self):
        super().__post_init__()
        if self.msaa not in (1, 2, 4, 8):
            raise ValueError(f"msaa must be 1, 2, 4 or 8, got {self.msaa}")
        if self.wave_size not in (32, 64):
            raise ValueError(f"wave_size must be 32 or 64, got {self.wave_size}")
        # Nothing accepted and ignored: a setting that cannot act in this config is refused.
        if self.per_sample_shading and self.msaa == 1:
            raise ValueError("per_sample_shading = true has no effect with msaa = 1 (one sample "
                             "per pixel, nothing to shade per sample); set msaa to 2, 4 or 8")


def pack_gbuffer(pts: SurfacePoints):
    cols = []
    for name, _ in GBUFFER_LAYOUT:
        v = getattr(pts, name)
        if name == "material":
            v = jax.lax.bitcast_convert_type(v.astype(jnp.int32), jnp.float32)[:, None]
        cols.append(v)
    return jnp.concatenate(cols, axis=-1)


def unpack_gbuffer(rows, camera, live) -> SurfacePoints:
    fields, at = {}, 0
    for name, c in GBUFFER_LAYOUT:
        fields[name] = rows[:, at:at + c]
        at += c
    mat = jax.lax.bitcast_convert_type(fields.pop("material")[:, 0], jnp.int32)
    pos = fields["position"]
    view = safe_normalize(camera.eye[None, :] - pos, fields["normal"])
    return SurfacePoints(view=view, material=mat, tri_id=jnp.where(live, 0, -1), valid=live,
                         **fields)


@register_frame("deferred", DeferredConfig)
def frame(scene, camera, cfg: DeferredConfig) -> Frame:
    """Deferred shading: G-buffer pass, then one shade per covered pixel (bytes counted)."""
    w, h = cfg.width, cfg.height
    n_pix = w * h
    offsets = sample_patterns.msaa(cfg.msaa) if cfg.msaa > 1 else sample_patterns.CENTER
    n_s = len(offsets)
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg, offsets)
        tri = vis.tri_id.reshape(n_s, n_pix)
        flat = lambda a: a.reshape(n_s * n_pix, 3)  # noqa: E731
        bary, ddx, ddy = flat(vis.bary), flat(vis.dbary_dx), flat(vis.dbary_dy)
        tri_f = tri.reshape(-1)
        covered = tri_f >= 0

    with jax.named_scope("gbuffer"):
        gbuf, gc = dispatch_points(
            covered,
            lambda it: surface_points(scene, camera, tri_f[it], bary[it], ddx[it], ddy[it]),
            pack_gbuffer,
            jnp.zeros((n_s * n_pix, GBUFFER_CHANNELS), jnp.float32), cfg.chunk)

    with jax.named_scope("classify"):
        # The pixel's representative sample: its first covered one.
        cov = tri >= 0  # [S, P]
        rep = jnp.argmax(cov, axis=0).astype(jnp.int32)  # [P]
        pix_cov = jnp.any(cov, axis=0)
        s_idx = jnp.arange(n_s, dtype=jnp.int32)[:, None]
        active = (s_idx == rep[None, :]) & pix_cov[None, :]
        if n_s > 1 and cfg.per_sample_shading:
            rep_tri = jnp.take_along_axis(tri, rep[None, :], axis=0)
            active = active | (cov & (tri != rep_tri))
        active = active.reshape(-1)

    with jax.named_scope("lighting"):
        lit, lc = dispatch_points(
            active,
            lambda it: unpack_gbuffer(gbuf[it], camera, jnp.ones(it.shape, bool)),
            lambda pts: shade(pts, scene),
            jnp.zeros((n_s * n_pix, 3), jnp.float32), cfg.chunk)

    with jax.named_scope("resolve"):
        lit = lit.reshape(n_s, n_pix, 3)
        act = active.reshape(n_s, n_pix)
        rep_c = jnp.take_along_axis(lit, rep[None, :, None], axis=0)  # [1, P, 3]
        c = jnp.where(act[..., None], lit, rep_c)
        c = jnp.where(cov[..., None], c, 0.0)
        image = jnp.mean(c, axis=0).reshape(h, w, 3)
        image = poison_on_overflow(image, vis.counts["overflow"])

    with jax.named_scope("counts"):
        n_cov = jnp.sum(pix_cov, dtype=jnp.int32)
        ws = cfg.wave_size
        waves, util = tile_waves(pix_cov.reshape(h, w), ws, lc["invocations"])
        px_bytes = GBUFFER_CHANNELS * 4
        written = gc["invocations"] * (px_bytes + DEPTH_BYTES)
        read = lc["invocations"] * px_bytes
        counts = make_counts(
            shade_invocations=lc["invocations"], covered_pixels=n_cov, waves=waves,
            lane_utilization=util, bytes_intermediate=written + read,
            gbuffer_bytes_written=written, gbuffer_bytes_read=read,
            gbuffer_invocations=gc["invocations"], alpha_invocations=vis.counts["alpha_invocations"],
            overflow=vis.counts["overflow"])
    return Frame(image, counts, {"shade_count": jnp.sum(act, axis=0, dtype=jnp.int32).reshape(h, w)})

render = REGISTRY["deferred"].render  # the compiled, overflow-checked entry

def tile_waves(active, wave_size: int, invocations):
    """Waves of a full-screen compute pass over 8x8 tiles: each tile is split into
    64 / wave_size waves of consecutive rows; a wave runs if any of its pixels is active.
    Returns (waves int32, lane utilisation = invocations / (waves * wave_size))."""
    h, w = active.shape
    th, tw = -(-h // 8), -(-w // 8)
    pad = jnp.zeros((th * 8, tw * 8), bool).at[:h, :w].set(active)
    rows = 64 // wave_size
    per = pad.reshape(th, 8, tw, 8).transpose(0, 2, 1, 3).reshape(th * tw, rows, -1)
    waves = jnp.sum(jnp.any(per, axis=-1), dtype=jnp.int32)
    util = invocations.astype(jnp.float32) / jnp.maximum(waves * wave_size, 1).astype(jnp.float32)
    return waves, util
