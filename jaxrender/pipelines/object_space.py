"""Object-space (decoupled, texture-space) shading with visibility-driven shadel allocation, as in
Oxide Games' Nitrous engine (GDC 2016; Baker and Jarzynski 2022).

  charts (os_charts) -> virtual shade sheets + triangle-id maps (os_sheet), built once on the host
  visibility buffer -> per-pixel filter taps -> marked 8x8 chunks (os_marking)
  -> chunks allocated into a fixed store, global MIP bias raised until they fit (os_alloc),
     or, with ``bias_feedback``, set from the previous frame's request (os_budget)
  -> owned shadels of the allocated chunks shaded through the chunked dispatch
  -> final pass: every covered pixel samples the store (bilinear / trilinear / anisotropic).

Static: the sheet (``prepare``). State: the store. ``render`` renders one frame from an empty
store; in a sequence (``render_sequence``, studies) the store is carried: shading happens every
``shade_every``-th frame (the frames between reuse the store and only shade chunks that became
visible), and with ``reuse`` a chunk resident in the previous frame is copied instead of shaded
when its inputs did not change (no view-dependent effect, or the eye did not move).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.base import BlendingConfig, poison_on_overflow
from jaxrender.pipelines.os_alloc import allocate
from jaxrender.pipelines.os_budget import check_config, feedback_allocate
from jaxrender.pipelines.os_counts import frame_counts
from jaxrender.pipelines.os_marking import footprint
from jaxrender.pipelines.os_sheet import CHUNK, LANES, ShadeSheet, build_sheet
from jaxrender.pipelines.registry import REGISTRY, register
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.os_transparency import (blend_layers, merge_os_counts,
                                                 over_transparent_samples, pixel_rows,
                                                 transparent_shadels)
from jaxrender.pipelines.visibility import share_visibility, visibility
from jaxrender.pipelines.waves import check_wave_size
from jaxrender.shading import shade, surface_points
from jaxrender.types import Array, Frame, pytree_dataclass

FILTERS = ("bilinear", "trilinear")


@dataclass(frozen=True)
class ObjectSpaceConfig(BlendingConfig):
    """store_shadels: physical store capacity in shadels (0 = 6 per pixel), rounded up to whole
    8x8 chunks; store_per_pixel > 0 sizes it in shadels per pixel of the output instead (so a
    study's sweep keeps its meaning at any resolution; store_shadels is then refused). mip_bias: the starting global MIP bias; bias_step: how much it is raised per
    retry when the marked chunks do not fit. bias_feedback: instead of retrying within the frame,
    carry the bias across frames (os_budget: frame t+1's bias from frame t's request, raised by
    bias_step over budget, relaxed by bias_relax below bias_low x the store, never below
    mip_bias; chunks that do not fit are left unshaded, their pixels read the coarsest level).
    filter: "trilinear" or "bilinear"; aniso_taps:
    taps along the footprint's major axis (1 = isotropic). eps: barycentric clamp
    [-eps, 1 + eps] for shadels outside their owner triangle (Oxide: 1). sheet_resolution:
    level-0 shadels per side for every object (0 = per object from texel_density in shadels per
    world unit and the materials' texture/stripe resolution, capped at max_sheet_resolution).
    With sheet_resolution > 0, texel_density is unused and max_sheet_resolution only caps it, so
    a non-default texel_density, a sheet_resolution above max_sheet_resolution and a
    non-default max_sheet_resolution that lifts no cap (sheet_resolution <= 4096) are refused.
    xatlas_resolution, force_xatlas: chart generation. shade_every, reuse: temporal decoupling
    in sequences. wave_size: lanes per wave for the wave counts (a chunk is 64 lanes).
    """

    store_shadels: int = 0
    store_per_pixel: float = 0.0
    mip_bias: float = 0.0
    bias_step: float = 0.25
    filter: str = "trilinear"
    aniso_taps: int = 1
    eps: float = 1.0
    sheet_resolution: int = 0
    texel_density: float = 128.0
    max_sheet_resolution: int = 4096
    xatlas_resolution: int = 1024
    force_xatlas: bool = False
    shade_every: int = 1
    reuse: bool = True
    wave_size: int = 32
    bias_feedback: bool = False
    bias_low: float = 0.8
    bias_relax: float = 0.0625

    def __post_init__(self):
        super().__post_init__()
        if self.filter not in FILTERS:
            raise ValueError(f"filter must be one of {FILTERS}, got {self.filter!r}")
        checks = {"store_shadels": self.store_shadels >= 0,
                  "store_per_pixel": self.store_per_pixel >= 0, "bias_step": self.bias_step > 0,
                  "aniso_taps": self.aniso_taps >= 1, "eps": self.eps >= 0,
                  "sheet_resolution": self.sheet_resolution >= 0,
                  "texel_density": self.texel_density > 0,
                  "max_sheet_resolution": self.max_sheet_resolution >= CHUNK,
                  "shade_every": self.shade_every >= 1}
        for k, ok in checks.items():
            if not ok:
                raise ValueError(f"object_space: invalid {k} = {getattr(self, k)!r}")
        check_wave_size(self.wave_size)
        if self.store_per_pixel > 0 and self.store_shadels != 0:
            raise ValueError(f"object_space: store_shadels = {self.store_shadels!r} has no "
                             f"effect with store_per_pixel = {self.store_per_pixel!r} > 0")
        check_config(self)
        # Nothing accepted and ignored: an explicit sheet_resolution replaces the per-object
        # sizing (texel_density); max_sheet_resolution then only caps it.
        if self.sheet_resolution > 0:
            cls = type(self)
            why = (f"with sheet_resolution = {self.sheet_resolution} > 0 (it sizes the sheets "
                   f"when sheet_resolution = 0)")
            if self.texel_density != cls.texel_density:
                raise ValueError(f"object_space: texel_density = {self.texel_density!r} has no "
                                 f"effect {why}")
            if self.sheet_resolution > self.max_sheet_resolution:
                raise ValueError(f"object_space: sheet_resolution = {self.sheet_resolution} "
                                 f"exceeds max_sheet_resolution = {self.max_sheet_resolution} "
                                 f"and would be capped to it")
            if self.max_sheet_resolution != cls.max_sheet_resolution \
                    and self.sheet_resolution <= cls.max_sheet_resolution:
                raise ValueError(f"object_space: max_sheet_resolution = "
                                 f"{self.max_sheet_resolution!r} has no effect {why}, unless "
                                 f"it lifts the cap for a sheet_resolution above "
                                 f"{cls.max_sheet_resolution}")

    def overflow_hint(self) -> str:
        what = ("the store holds not even the coarsest chunk of every visible object"
                if self.bias_feedback else
                "the marked chunks do not fit the store even at the largest MIP bias")
        return (f"{what} (or fragments overflowed); raise store_shadels (now "
                f"{self.store_chunks * LANES}) or fragment_capacity (now {self.capacity})")

    @property
    def store_chunks(self) -> int:
        if self.store_per_pixel > 0:
            shadels = math.ceil(self.store_per_pixel * self.width * self.height)
        else:
            shadels = int(self.store_shadels or 6 * self.width * self.height)
        return max(1, -(-shadels // LANES))


@pytree_dataclass
class StoreState:
    """The physical store carried between frames: page int32[NC] (slot of each virtual chunk,
    -1 not resident), colour float32[cap * 64, 3], eye float32[3] of the frame it was shaded;
    with bias_feedback, bias float32 (the next frame's MIP bias; None without)."""

    page: Array
    colour: Array
    eye: Array
    bias: Array | None = None


def empty_state(sheet: ShadeSheet, cfg: ObjectSpaceConfig) -> StoreState:
    bias = jnp.float32(cfg.mip_bias) if cfg.bias_feedback else None
    return StoreState(jnp.full((sheet.n_chunks,), -1, jnp.int32),
                      jnp.zeros((cfg.store_chunks * LANES, 3), jnp.float32),
                      jnp.full((3,), jnp.nan, jnp.float32), bias)


def prepare(scene, cfg: ObjectSpaceConfig) -> ShadeSheet:
    """The scene's charts, virtual sheets and triangle-id maps (host, cached)."""
    return build_sheet(scene, cfg)


# ---------------------------------------------------------------- shadel -> surface point


def shadel_barycentrics(corner: Array, p: Array, eps: float):
    """Barycentrics of chart points p float32[N, 2] in chart triangles corner float32[N, 3, 2],
    clamped to [-eps, 1 + eps] (then shifted to sum to 1), and their d/ds, d/dt."""
    a, b, c = corner[:, 0], corner[:, 1], corner[:, 2]
    v0, v1, d = b - a, c - a, p - a
    det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    ok = jnp.abs(det) > 1e-20
    inv = jnp.where(ok, 1.0 / jnp.where(ok, det, 1.0), 0.0)
    b1 = (d[:, 0] * v1[:, 1] - d[:, 1] * v1[:, 0]) * inv
    b2 = (v0[:, 0] * d[:, 1] - v0[:, 1] * d[:, 0]) * inv
    bary = jnp.stack([1.0 - b1 - b2, b1, b2], axis=-1)
    bary = jnp.clip(bary, -eps, 1.0 + eps)
    bary = bary + (1.0 - jnp.sum(bary, axis=-1, keepdims=True)) / 3.0
    bary = jnp.where(ok[:, None], bary, jnp.float32(1.0 / 3.0))
    d1 = jnp.stack([v1[:, 1], -v1[:, 0]], -1) * inv[:, None]  # d b1 / d(s, t)
    d2 = jnp.stack([-v0[:, 1], v0[:, 0]], -1) * inv[:, None]
    dst = jnp.stack([-(d1 + d2), d1, d2], axis=1)  # [N, 3, 2]
    return bary, dst[..., 0], dst[..., 1]


def shadel_points(scene, camera, sheet: ShadeSheet, slot_chunk: Array, items: Array, eps: float):
    """SurfacePoints at the centres of store shadels ``items`` (slot * 64 + lane); the uv
    derivatives are one shadel step of the shadel's level (the shading rate)."""
    slot, lane = items // LANES, items % LANES
    v = jnp.maximum(slot_chunk[slot], 0)
    tri = sheet.owner[v * LANES + lane]
    lvl, obj = sheet.chunk_level[v], sheet.chunk_obj[v]
    rl = jnp.right_shift(sheet.obj_res[obj], lvl).astype(jnp.float32)
    x = (sheet.chunk_cx[v] * CHUNK + lane % CHUNK).astype(jnp.float32)
    y = (sheet.chunk_cy[v] * CHUNK + lane // CHUNK).astype(jnp.float32)
    p = jnp.stack([(x + 0.5) / rl, (y + 0.5) / rl], axis=-1)
    bary, dbds, dbdt = shadel_barycentrics(sheet.corner_st[jnp.maximum(tri, 0)], p, eps)
    return surface_points(scene, camera, tri, bary, dbds / rl[:, None], dbdt / rl[:, None])


# ---------------------------------------------------------------- one frame


class Residency(NamedTuple):
    """The store after marking and allocation: ``al`` (os_alloc's Allocation), ``live`` bool[cap]
    (slots in use), ``owned_slot`` bool[cap, 64] (the slot's shadels with an owner triangle),
    ``reused`` bool[cap] (slots whose colours are kept from the previous frame), ``colour``
    float32[cap * 64, 3] (the kept colours, 0 elsewhere) and, with bias_feedback,
    ``budget`` (os_budget's Budget; None without). Only the slots' rows of the sheet's owner
    map are read: the whole map is 64 shadels per virtual chunk (150 M on thin at 1080p)."""

    al: object
    live: Array
    owned_slot: Array
    reused: Array
    colour: Array
    budget: object = None


class Resolved(NamedTuple):
    image: Array
    missing: Array  # taps whose chunk is not resident
    unowned: Array  # taps that read a shadel no triangle owns
    overflow: Array
    rows: Array  # every tapped sample's read: the pixels', then any transparent fragments'


def plan_store(scene, sheet: ShadeSheet, camera, cfg: ObjectSpaceConfig, state: StoreState,
               fp, shade_frame: Array) -> Residency:
    """Mark the chunks the screen reads, allocate them in the store, and keep the colours of
    those resident from the previous frame when nothing they depend on changed."""
    cap = cfg.store_chunks
    with jax.named_scope("mark_allocate"):
        if cfg.bias_feedback:
            al, budget = feedback_allocate(fp, sheet, cfg, state.bias)
        else:
            al, budget = allocate(fp, sheet, cap, cfg.mip_bias, cfg.bias_step, cfg.filter,
                                  cfg.aniso_taps), None
        live = jnp.arange(cap, dtype=jnp.int32) < al.n_alloc  # slots in use
        v_of_slot = jnp.maximum(al.slot_chunk, 0)
        owned_slot = (sheet.owner.reshape(sheet.n_chunks, LANES)[v_of_slot] >= 0) & live[:, None]
    with jax.named_scope("reuse"):
        view_dependent = bool(scene.effects.specular)
        same_inputs = jnp.all(state.eye == camera.eye) if view_dependent else jnp.bool_(True)
        if scene.effects.motion:  # moving surfaces are lit anew
            same_inputs = jnp.bool_(False)
        may_reuse = ~shade_frame | (same_inputs & cfg.reuse)
        prev = state.page[v_of_slot]
        reused = live & (prev >= 0) & may_reuse  # [cap]
        src = jnp.maximum(prev, 0)[:, None] * LANES + jnp.arange(LANES, dtype=jnp.int32)[None, :]
        colour = jnp.where(reused[:, None, None], state.colour[src],
                           0.0).reshape(cap * LANES, 3)
    return Residency(al, live, owned_slot, reused, colour, budget)


def resolve_taps(colour: Array, sheet: ShadeSheet, al, vis, cfg) -> Resolved:
    """Each pixel's filtered read of the store (its taps' weighted sum)."""
    t = al.taps
    slot = al.page[t.chunk]
    use = t.weight > 0.0
    addr = jnp.where(use & (slot >= 0), slot * LANES + t.lane, 0)
    weight = jnp.where(use & (slot >= 0), t.weight, 0.0)
    # Tap by tap, written out: as one sum over the tap axis XLA writes every product [P, K, 3]
    # to memory before adding them up.
    image = colour[addr[:, 0]] * weight[:, 0, None]
    for k in range(1, addr.shape[1]):
        image = image + colour[addr[:, k]] * weight[:, k, None]
    rows, image = image, image[:cfg.width * cfg.height].reshape(cfg.height, cfg.width, 3)
    missing = jnp.sum(use & (slot < 0), dtype=jnp.int32)
    unowned = jnp.sum(use & (sheet.owner[t.chunk * LANES + t.lane] < 0), dtype=jnp.int32)
    overflow = al.overflow + vis.counts["overflow"] + (missing > 0).astype(jnp.int32)
    return Resolved(poison_on_overflow(image, overflow), missing, unowned, overflow, rows)


def frame_step(scene, sheet: ShadeSheet, camera, cfg: ObjectSpaceConfig, state: StoreState,
               shade_frame: Array) -> tuple[Frame, StoreState]:
    """One frame from the store of the previous one. ``shade_frame`` (bool scalar): this is a
    shading frame; otherwise every resident chunk is reused."""
    n_pix = cfg.width * cfg.height
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg)
        flat = lambda a: a.reshape((n_pix,) + a.shape[2:])  # noqa: E731
        fp = footprint(scene, sheet, flat(vis.tri_id), flat(vis.bary), flat(vis.dbary_dx),
                       flat(vis.dbary_dy))
    # Transparent layers in front of the opaque depth are samples too: they mark chunks.
    return over_transparent_samples(
        scene, sheet, camera, cfg, vis, fp,
        lambda fp_all, blended: shade_and_resolve(scene, sheet, camera, cfg, state, shade_frame,
                                                  vis, fp, fp_all, blended))


def shade_and_resolve(scene, sheet: ShadeSheet, camera, cfg: ObjectSpaceConfig,
                      state: StoreState, shade_frame: Array, vis, fp, fp_all, blended):
    """The frame from its samples' footprints ``fp_all`` (the pixels' ``fp``, then any
    transparent fragments', ``blended``): the store planned, shaded and read."""
    n_pix = cfg.width * cfg.height
    res = plan_store(scene, sheet, camera, cfg, state, fp_all, shade_frame)
    with jax.named_scope("shade"):
        active = (res.owned_slot & (res.live & ~res.reused)[:, None]).reshape(-1)
        # The chunk is sized for half a screen of shadels, not for the store: the store holds
        # many times what a frame shades (12.4M shadels on foliage at 1080p, for 750k in a
        # shading frame and a few hundred in a reusing one), and a chunk sized to it launched
        # 2^18 lanes a frame for those few (RESULTS.md, twenty-fifth session).
        colour, work = dispatch.shade(
            dispatch.WorkList.of(active),
            lambda it: shadel_points(scene, camera, sheet, res.al.slot_chunk, it, cfg.eps),
            lambda pts: shade(pts, scene), res.colour,
            dispatch.resolve_chunk(cfg.chunk, n_pix // 2))
    with jax.named_scope("resolve"):
        out = resolve_taps(colour, sheet, res.al, vis, cfg)
    image, layered = blend_layers(scene, camera, blended, out.rows, out.image, cfg)
    with jax.named_scope("counts"):
        pix_res = res if blended is None else res._replace(
            al=res.al._replace(taps=pixel_rows(res.al.taps, n_pix)))
        counts, aux = frame_counts(scene, sheet, cfg, fp, pix_res, work, out, vis)
        if blended is not None:
            counts = merge_os_counts(counts, layered, transparent_shadels(
                scene, sheet, res.al.slot_chunk, work))
        counts.update(vertex_counts(scene, full_passes=1))  # the raster pass
    image = poison_on_overflow(image, counts["overflow"])
    new_state = StoreState(res.al.page, colour,
                           jnp.where(shade_frame, camera.eye, state.eye).astype(jnp.float32),
                           None if res.budget is None else res.budget.next_bias)
    return Frame(image, counts, share_visibility(aux, vis, cfg)), new_state


# ---------------------------------------------------------------- the registered pipeline


def init(scene, sheet: ShadeSheet, camera, cfg: ObjectSpaceConfig) -> StoreState:
    return empty_state(sheet, cfg)


@register("object_space", ObjectSpaceConfig, init=init, prepare=prepare)
def step(scene, sheet: ShadeSheet, state: StoreState, camera, t, cfg: ObjectSpaceConfig):
    """Object-space shading: visible 8x8 shadel chunks shaded in texture space, then sampled."""
    return frame_step(scene, sheet, camera, cfg, state, t % cfg.shade_every == 0)


render = REGISTRY["object_space"].render
render_sequence = REGISTRY["object_space"].render_sequence

__all__ = ["ObjectSpaceConfig", "StoreState", "empty_state", "frame_step", "prepare", "render",
           "render_sequence", "shadel_barycentrics", "shadel_points", "step"]
