"""Deferred shading: a G-buffer pass writes each visible surface's attributes, then a lighting
pass shades every covered pixel once from the G-buffer.

The G-buffer is real: the attribute pass writes the ``gbuffer.GBUFFER_LAYOUT`` channels of
every covered pixel (sample) into full-screen float32 planes through the chunked dispatch, and
the lighting pass reads them back and calls the shared ``shade``. The bytes written and read
are the planes' bytes times the pixels (samples) that the two work lists touched. Under MSAA
the G-buffer holds every sample; lighting shades one representative sample per pixel and, with
``per_sample_shading``, also every sample whose surface differs from it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
import jaxrender.raster.samples as sample_patterns
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.gbuffer import (DEPTH_BYTES, PIXEL_BYTES, empty_gbuffer,
                                         gbuffer_entries, gbuffer_fields, unpack_gbuffer)
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.transparency import merge_counts, refuse_transparency, transparent_pass
from jaxrender.pipelines.visibility import share_visibility, visibility
from jaxrender.pipelines.waves import check_wave_size, tile_waves
from jaxrender.shading import shade, surface_points
from jaxrender.types import Array, Frame

@dataclass(frozen=True)
class DeferredConfig(BlendingConfig):
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
        check_wave_size(self.wave_size)
        # Nothing accepted and ignored: a setting that cannot act in this config is refused.
        if self.per_sample_shading and self.msaa == 1:
            raise ValueError("per_sample_shading = true has no effect with msaa = 1 (one sample "
                             "per pixel, nothing to shade per sample); set msaa to 2, 4 or 8")


class LightingPlan(NamedTuple):
    """Which samples the lighting pass shades, per (sample, pixel): ``active`` bool[S, P] (flat,
    sample index s * P + p); ``covered`` bool[S, P]; per pixel ``rep`` int32[P], its
    representative sample (its first covered one), and ``pixel_covered`` bool[P]."""

    active: Array
    covered: Array
    rep: Array
    pixel_covered: Array


def gbuffer_pass(scene, camera, vis, n_samples: int, cfg):
    """The attribute pass: every covered sample's G-buffer row, through ``dispatch.shade_screen``.
    Returns (the G-buffer's fields, float32[S * P, channels] each, and its WorkList)."""
    n = n_samples * cfg.width * cfg.height
    tri = vis.tri_id.reshape(-1)
    flat = lambda a: a.reshape(n, 3)  # noqa: E731
    bary, ddx, ddy = flat(vis.bary), flat(vis.dbary_dx), flat(vis.dbary_dy)
    return dispatch.shade_screen(
        tri >= 0, lambda it: surface_points(scene, camera, tri[it], bary[it], ddx[it], ddy[it]),
        gbuffer_fields, empty_gbuffer(n), cfg.chunk)


def lighting_plan(vis, n_samples: int, cfg: DeferredConfig) -> LightingPlan:
    """One representative sample per covered pixel and, with ``per_sample_shading``, every
    sample whose triangle differs from it."""
    tri = vis.tri_id.reshape(n_samples, cfg.width * cfg.height)
    cov = tri >= 0  # [S, P]
    rep = jnp.argmax(cov, axis=0).astype(jnp.int32)  # [P]
    pix_cov = jnp.any(cov, axis=0)
    s_idx = jnp.arange(n_samples, dtype=jnp.int32)[:, None]
    active = (s_idx == rep[None, :]) & pix_cov[None, :]
    if n_samples > 1 and cfg.per_sample_shading:
        rep_tri = jnp.take_along_axis(tri, rep[None, :], axis=0)
        active = active | (cov & (tri != rep_tri))
    return LightingPlan(active, cov, rep, pix_cov)


def resolve_samples(lit: Array, plan: LightingPlan, cfg) -> Array:
    """Samples not shaded take their pixel's representative colour; the box filter over the
    samples of each pixel (uncovered samples black). Returns float32[H, W, 3]."""
    n_s, n_pix = plan.active.shape
    lit = lit.reshape(n_s, n_pix, 3)
    rep_c = jnp.take_along_axis(lit, plan.rep[None, :, None], axis=0)  # [1, P, 3]
    c = jnp.where(plan.active[..., None], lit, rep_c)
    c = jnp.where(plan.covered[..., None], c, 0.0)
    return jnp.mean(c, axis=0).reshape(cfg.height, cfg.width, 3)


@register_frame("deferred", DeferredConfig)
def frame(scene, camera, cfg: DeferredConfig) -> Frame:
    """Deferred shading: G-buffer pass, then one shade per covered pixel (bytes counted)."""
    offsets = sample_patterns.msaa(cfg.msaa) if cfg.msaa > 1 else sample_patterns.CENTER
    n_s = len(offsets)
    if n_s > 1:
        refuse_transparency(scene, "deferred with msaa > 1")
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg, offsets)
    with jax.named_scope("gbuffer"):
        gbuf, attributes = gbuffer_pass(scene, camera, vis, n_s, cfg)
    with jax.named_scope("plan"):
        plan = lighting_plan(vis, n_s, cfg)
    with jax.named_scope("lighting"):
        lit, lighting = dispatch.shade_screen(
            plan.active.reshape(-1),
            lambda it: unpack_gbuffer(gbuffer_entries(gbuf, it), camera, jnp.ones(it.shape, bool)),
            lambda pts: shade(pts, scene), jnp.zeros((plan.active.size, 3), jnp.float32),
            cfg.chunk)
    with jax.named_scope("resolve"):
        image = resolve_samples(lit, plan, cfg)
    image, blended = transparent_pass(scene, camera, image, vis.depth, cfg)
    with jax.named_scope("counts"):
        counts = merge_counts(_counts(vis, plan, attributes, lighting, cfg), blended)
        counts.update(vertex_counts(scene, full_passes=1))  # the G-buffer pass
    image = poison_on_overflow(image, counts["overflow"])
    shade_count = jnp.sum(plan.active, axis=0, dtype=jnp.int32).reshape(cfg.height, cfg.width)
    return Frame(image, counts, share_visibility({"shade_count": shade_count}, vis, cfg))


def _counts(vis, plan: LightingPlan, attributes: dispatch.WorkList,
            lighting: dispatch.WorkList, cfg: DeferredConfig) -> dict:
    waves, util = tile_waves(plan.pixel_covered.reshape(cfg.height, cfg.width), cfg.wave_size,
                             lighting.invocations)
    written = attributes.invocations * (PIXEL_BYTES + DEPTH_BYTES)
    read = lighting.invocations * PIXEL_BYTES
    return make_counts(
        shade_invocations=lighting.invocations,
        covered_pixels=jnp.sum(plan.pixel_covered, dtype=jnp.int32), waves=waves,
        lane_utilization=util, bytes_intermediate=written + read,
        gbuffer_bytes_written=written, gbuffer_bytes_read=read,
        gbuffer_invocations=attributes.invocations,
        alpha_invocations=vis.counts["alpha_invocations"], overflow=vis.counts["overflow"])


render = REGISTRY["deferred"].render  # the compiled, overflow-checked entry
