"""Checkerboard rendering: shade half of the pixels each frame, reconstruct the other half.

Sampling plan: pixel (x, y) of frame t is shaded when (x + y + frame + t) is even, so the two
halves alternate every frame. ``pattern="checker"`` shades full-resolution pixels;
``pattern="2x1"`` is half-width rendering with 2 samples per pixel (checkerboard rendering as
consoles do it): the same checker of shaded samples, the other sample of each 2x1 pair covered
by the full-resolution visibility, but each shaded sample is one pixel of a half-width target,
so its texture footprint is two pixels wide (``lod_bias = -1`` compensates). A covered pixel
none of whose 4 neighbours is covered (a lone pixel, a 1-pixel-wide image) cannot be
reconstructed and is shaded as well (counted).

Reconstruction of a missing pixel, geometry-aware from a full-resolution visibility pass:

- temporal (``temporal = true``, frames t >= 1 of a sequence): the pixel is reprojected into
  frame t-1 through the known camera motion (``scene.reprojection.reproject``), or in a moving
  scene through its motion vectors (``raster.motion.reproject_with_motion``), and, of the 2x2
  pixels around that point, the nearest one shaded in frame t-1 with the same surface id is taken,
  unless the point is off screen or its depth disagrees (disocclusion); then
- spatial: the mean of the 4 neighbours (all shaded this frame) that show the same surface id;
  when none does, the neighbour nearest in depth.

State: the previous frame's History. ``render`` (one frame from an empty history) is the
spatial-only first frame; ``render_sequence`` and studies run the technique as shipped.
Counts: ``shade_invocations`` (pixels shaded), ``reconstruction_reads`` (neighbour colours
read + history colours read), split into ``spatial_reads`` and ``history_reads``;
``history_rejected``, ``orphans_shaded``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.gbuffer import shade_through
from jaxrender.pipelines.pixel_ids import (
    ID_KINDS,
    check_choice,
    inside,
    lod_scaled,
    shift,
    surface_ids,
)
from jaxrender.pipelines.registry import REGISTRY, register
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.transparency import merge_counts, transparent_pass
from jaxrender.pipelines.visibility import (Previous, points_from_vis, share_visibility,
                                            visibility)
from jaxrender.pipelines.waves import check_wave_size, tile_waves
from jaxrender.raster.motion import reproject_with_motion
from jaxrender.scene.animation import positions_at
from jaxrender.scene.camera import Camera
from jaxrender.scene.reprojection import DEFAULT_DEPTH_TOLERANCE, reproject
from jaxrender.types import Array, Frame

PATTERNS = ("checker", "2x1")
NEIGHBOURS = ((0, -1), (0, 1), (-1, 0), (1, 0))  # (dy, dx): left, right, up, down


@dataclass(frozen=True)
class CheckerboardConfig(BlendingConfig):
    """pattern: ``checker`` (pixel checker) or ``2x1`` (half-width, 2 samples per pixel).
    frame: frame-index offset of the checker (frame t shades parity frame + t).
    temporal: reuse the reprojected previous frame (frames after the first of a sequence);
    false: the spatial-only variant.
    ids: surface id used for reconstruction and rejection (triangle, object, material, none).
    lod_bias: texture LOD bias (-1: one MIP level sharper). depth_tolerance: relative linear
    depth difference at which history is rejected (only with ``temporal``: a non-default value
    with ``temporal = false`` is refused). wave_size: lanes per wave (counts only)."""

    pattern: str = "checker"
    frame: int = 0
    temporal: bool = True
    ids: str = "object"
    lod_bias: float = 0.0
    depth_tolerance: float = DEFAULT_DEPTH_TOLERANCE
    wave_size: int = 32

    def __post_init__(self):
        super().__post_init__()
        check_choice("pattern", self.pattern, PATTERNS)
        check_choice("ids", self.ids, ID_KINDS)
        check_wave_size(self.wave_size)
        if not float(self.depth_tolerance) > 0.0:
            raise ValueError(f"depth_tolerance must be > 0, got {self.depth_tolerance}")
        # Nothing accepted and ignored: a setting that cannot act in this config is refused.
        if not self.temporal and float(self.depth_tolerance) != type(self).depth_tolerance:
            raise ValueError(f"depth_tolerance = {self.depth_tolerance} has no effect with "
                             f"temporal = false (it rejects reprojected history, which only the "
                             f"temporal variant reads)")


class History(NamedTuple):
    """What frame t keeps for frame t+1: its output, which of its pixels were shaded, surface
    ids, depth and camera; ``valid`` False before the first frame."""

    image: Array
    shaded: Array
    ids: Array
    depth: Array
    camera: Camera
    valid: Array


def checker_mask(height: int, width: int, t: Array) -> Array:
    """bool[H, W]: the pixels shaded at frame index ``t`` (traced int)."""
    y = jnp.arange(height, dtype=jnp.int32)[:, None]
    x = jnp.arange(width, dtype=jnp.int32)[None, :]
    return (x + y + jnp.asarray(t, jnp.int32)) % 2 == 0


def _spatial(img, ids, depth, ncov):
    """Geometry-aware 4-neighbour reconstruction of every pixel (used where missing)."""
    cs = [shift(img, dy, dx) for dy, dx in NEIGHBOURS]
    ok = [nc & (shift(ids, dy, dx, -2) == ids) for nc, (dy, dx) in zip(ncov, NEIGHBOURS)]
    okf = [o.astype(jnp.float32)[..., None] for o in ok]
    wsum = sum(okf)
    avg = sum(o * c for o, c in zip(okf, cs)) / jnp.maximum(wsum, 1.0)
    # The neighbour nearest in depth, the first of equals (as argmin), by running comparisons:
    # an argmin over a stacked axis of 4 compiles to a slow variadic reduction on a GPU.
    inf = jnp.float32(jnp.inf)
    nearest, best = cs[0], None
    for c, nc, (dy, dx) in zip(cs, ncov, NEIGHBOURS):
        d = jnp.where(nc, jnp.abs(shift(depth, dy, dx, 0.0) - depth), inf)
        if best is None:
            best = d
            continue
        take = d < best
        nearest = jnp.where(take[..., None], c, nearest)
        best = jnp.where(take, d, best)
    return jnp.where(wsum > 0.0, avg, nearest)


def _history_sample(prev: History, position: Array, ids: Array):
    """The previous frame's sample nearest to each reprojected position among the 2x2 pixels
    around it that were shaded in that frame (a checker holds two of them) and show the same
    surface id: (colour float32[H, W, 3], found bool[H, W]). Only shaded samples are history:
    a pixel that was itself reconstructed would feed each frame's resampling error into the
    next, and the nearest pixel alone is unshaded half of the time."""
    h, w = ids.shape
    u, v = position[..., 0] - 0.5, position[..., 1] - 0.5
    x0, y0 = jnp.floor(u).astype(jnp.int32), jnp.floor(v).astype(jnp.int32)
    best_d = jnp.full((h, w), jnp.inf, jnp.float32)
    colour = jnp.zeros((h, w, 3), jnp.float32)
    for dy in (0, 1):
        for dx in (0, 1):
            x, y = x0 + dx, y0 + dy
            inb = (x >= 0) & (x < w) & (y >= 0) & (y < h)
            xc, yc = jnp.clip(x, 0, w - 1), jnp.clip(y, 0, h - 1)
            ok = inb & prev.shaded[yc, xc] & (prev.ids[yc, xc] == ids)
            d = jnp.where(ok, (u - x.astype(jnp.float32)) ** 2 + (v - y.astype(jnp.float32)) ** 2,
                          jnp.inf)
            take = d < best_d
            colour = jnp.where(take[..., None], prev.image[yc, xc], colour)
            best_d = jnp.where(take, d, best_d)
    return colour, prev.valid & jnp.isfinite(best_d)


class CheckerPlan(NamedTuple):
    """Which pixels a frame shades: ``work`` (the flat pixels of ``active``), ``covered``,
    ``active`` (the checker's pixels plus orphans, covered ones only), ``orphan`` (missing pixels
    with no covered neighbour: shaded too), ``inside`` and ``neighbours`` (per NEIGHBOURS, the
    neighbour lies in the image / is covered)."""

    work: dispatch.WorkList
    covered: Array
    active: Array
    orphan: Array
    inside: list
    neighbours: list


def plan_checker(vis, t, cfg: CheckerboardConfig) -> CheckerPlan:
    h, w = cfg.height, cfg.width
    covered = vis.tri_id >= 0
    ins = [jnp.asarray(inside(h, w, dy, dx)) for dy, dx in NEIGHBOURS]
    ncov = [i & shift(covered, dy, dx, False) for i, (dy, dx) in zip(ins, NEIGHBOURS)]
    any_n = ncov[0] | ncov[1] | ncov[2] | ncov[3]
    pattern = checker_mask(h, w, cfg.frame + t)
    orphan = covered & ~pattern & ~any_n
    active = covered & (pattern | orphan)
    return CheckerPlan(dispatch.WorkList.of(active.reshape(-1)), covered, active, orphan, ins,
                       ncov)


def shade_checker(scene, camera, vis, plan: CheckerPlan, cfg: CheckerboardConfig):
    """The planned pixels shaded by the deferred lighting pass's path (as DACS), texture LOD
    scaled by ``lod_bias`` (and twice wider for ``2x1``). Returns (float32[H, W, 3], WorkList)."""
    h, w = cfg.height, cfg.width
    scale = 2.0 ** float(cfg.lod_bias)
    sx = scale * (2.0 if cfg.pattern == "2x1" else 1.0)
    img, work = dispatch.shade(
        plan.work, lambda items: lod_scaled(points_from_vis(scene, camera, vis, items), sx, scale),
        lambda pts: shade_through(pts, scene, camera, pts.valid),
        jnp.zeros((h * w, 3), jnp.float32), cfg.chunk)
    return img.reshape(h, w, 3), work


class Reconstruction(NamedTuple):
    image: Array
    use_history: Array
    rejected: Array


def reconstruct(img, vis, ids, camera, prev: History, plan: CheckerPlan,
                cfg: CheckerboardConfig) -> Reconstruction:
    """Missing pixels from the reprojected history where it holds the same surface, else from
    their neighbours."""
    h, w = cfg.height, cfg.width
    missing = plan.covered & ~plan.active
    with jax.named_scope("spatial"):
        spatial = _spatial(img, ids, vis.depth, plan.neighbours)
    with jax.named_scope("temporal"):
        if cfg.temporal:
            if vis.motion is not None:  # a moving scene: its motion vectors
                rp = reproject_with_motion(vis.motion, vis.prev_depth, plan.covered, camera,
                                           prev.camera, prev.depth, cfg.depth_tolerance)
            else:
                rp = reproject(vis.depth, camera, prev.camera, w, h, prev_depth=prev.depth,
                               depth_tolerance=cfg.depth_tolerance)
            hist_colour, hist_ok = _history_sample(prev, rp.position, ids)
            hist_ok = hist_ok & rp.valid
            use_hist = missing & hist_ok
            recon = jnp.where(use_hist[..., None], hist_colour, spatial)
            rejected = missing & prev.valid & ~hist_ok
        else:
            use_hist = rejected = jnp.zeros((h, w), bool)
            recon = spatial
    image = jnp.where(plan.active[..., None], img, jnp.where(missing[..., None], recon, 0.0))
    return Reconstruction(image, use_hist, rejected)


def checker_frame(scene, camera, t, prev: History, cfg: CheckerboardConfig):
    """One frame at traced index ``t`` given the previous frame's History (ignored when
    ``prev.valid`` is False or ``cfg.temporal`` is off). Returns (Frame, History)."""
    with jax.named_scope("visibility"):
        moving = cfg.temporal and scene.effects.motion
        previous = Previous(positions_at(scene, t - 1), prev.camera) if moving else None
        vis = visibility(scene, camera, cfg, previous=previous)
        ids = surface_ids(scene, vis.tri_id, cfg.ids)
    with jax.named_scope("plan"):
        plan = plan_checker(vis, t, cfg)
    with jax.named_scope("shade"):
        img, work = shade_checker(scene, camera, vis, plan, cfg)
    rec = reconstruct(img, vis, ids, camera, prev, plan, cfg)
    # The history holds the opaque resolve: the transparent layers are blended anew each
    # frame, as engines do, never reprojected into the opaque surfaces.
    opaque = poison_on_overflow(rec.image, vis.counts["overflow"])
    image, blended = transparent_pass(scene, camera, rec.image, vis.depth, cfg)
    with jax.named_scope("counts"):
        counts = merge_counts(_counts(vis, plan, rec, work, cfg), blended)
        counts.update(vertex_counts(scene, full_passes=1))  # the raster pass
    image = poison_on_overflow(image, counts["overflow"])
    aux = {"shaded": plan.active, "history": rec.use_history}
    frame = Frame(image, counts, share_visibility(aux, vis, cfg))
    return frame, History(opaque, plan.active, ids, vis.depth, camera, jnp.asarray(True))


def _counts(vis, plan: CheckerPlan, rec: Reconstruction, work: dispatch.WorkList,
            cfg: CheckerboardConfig) -> dict:
    n_in = sum(i.astype(jnp.int32) for i in plan.inside)
    missing = plan.covered & ~plan.active
    spatial_px = missing & ~rec.use_history
    spatial_reads = jnp.sum(jnp.where(spatial_px, n_in, 0), dtype=jnp.int32)
    history_reads = jnp.sum(rec.use_history, dtype=jnp.int32)
    waves, util = tile_waves(plan.active, cfg.wave_size, work.invocations)
    return make_counts(
        shade_invocations=work.invocations,
        covered_pixels=jnp.sum(plan.covered, dtype=jnp.int32),
        waves=waves, lane_utilization=util,
        reconstruction_reads=spatial_reads + history_reads, spatial_reads=spatial_reads,
        history_reads=history_reads, history_rejected=jnp.sum(rec.rejected, dtype=jnp.int32),
        orphans_shaded=jnp.sum(plan.orphan, dtype=jnp.int32),
        alpha_invocations=vis.counts["alpha_invocations"], overflow=vis.counts["overflow"])


def empty_history(camera, cfg) -> History:
    h, w = cfg.height, cfg.width
    return History(jnp.zeros((h, w, 3), jnp.float32), jnp.zeros((h, w), bool),
                   jnp.full((h, w), -1, jnp.int32), jnp.ones((h, w), jnp.float32), camera,
                   jnp.asarray(False))


def init(scene, static, camera, cfg: CheckerboardConfig) -> History:
    return empty_history(camera, cfg)


@register("checkerboard", CheckerboardConfig, init=init)
def step(scene, static, history: History, camera, t, cfg: CheckerboardConfig):
    """Checkerboard: half the pixels per frame, alternating; reprojected history, spatial fill."""
    return checker_frame(scene, camera, t, history, cfg)


render = REGISTRY["checkerboard"].render
render_sequence = REGISTRY["checkerboard"].render_sequence
