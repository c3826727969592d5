"""Visibility-buffer shading (Decima-style): the raster pass writes a 32-bit packed id per
pixel; shading decodes the id, fetches the triangle, computes perspective-correct barycentrics
and their analytic derivatives at the pixel, and shades. No quads, so no helper lanes.

Shading work is classified by loose tiling (``tiling = "loose"``, Decima's: inside each 128x128
tile the pixels of one batch group fill complete waves, with 16-bit pixel and 32-bit wave
commands; ``pipelines.loose_tiles``) or into 8x8 tiles per material (``tiling = "tiles"``, the
scheme the talk rejected), packed into waves of 32 or 64 lanes; the work list is in wave order,
and the wave and command counts are read off it.
Software VRS: each pixel gets a rate 1x1, 1x2, 2x1 or 2x2 (width x height) from a per-triangle
rule (view distance or screen-space speed), a rate image, or per 8x8 tile from the speed of
the frame's motion vectors (``vrs = "motion"``, camera motion included; ``pipelines.vrs``);
the pixels of one material and rate in one aligned coarse block share a single shade at the
block's first pixel, broadcast to them. Under 8x8 tiles, waves of coarse pixels are formed on
the coarse grid of their rate; under loose tiles a lane shades one coarse pixel, its rate in
its pixel command. With the micro-batch ids the rate travels in the id's top bits.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
import jaxrender.pipelines.micro_batch as micro_batch
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.id_layout import IdLayout, decode, encode, pack_ids  # noqa: F401
from jaxrender.pipelines.loose_tiles import TILINGS, command_counts, loose_order
from jaxrender.pipelines.micro_batch import RATE_BITS, MicroBatches, micro_batches
from jaxrender.pipelines.quads import BIG, first_of_segment_index, segment_starts
from jaxrender.pipelines.registry import REGISTRY, register
from jaxrender.pipelines.transparency import merge_counts, transparent_pass
from jaxrender.pipelines.vertex_work import VERTEX_FETCHES, vertex_counts, wave_triangles
from jaxrender.pipelines.visibility import (Previous, clip_vertices, points_at,
                                            share_visibility, visibility)
from jaxrender.pipelines.vrs import RATE_H, RATE_W, RATES, SPEED_MODES, VRS_MODES, pixel_rates
from jaxrender.pipelines.waves import TILE, check_wave_size
from jaxrender.scene.animation import positions_at
from jaxrender.shading import shade
from jaxrender.sorting import lex_sort
from jaxrender.types import Array, Frame

ID_LAYOUTS = ("micro_batch", "fixed")


@dataclass(frozen=True)
class VisBufferConfig(BlendingConfig):
    """id_layout: micro_batch (Decima's: 16-bit micro batch, then primitive and instance bits
    sized per batch, the VRS rate in the top 2 bits; ``pipelines.micro_batch``) or fixed (the
    fields below). batch_bits / primitive_bits / instance_bits: the fixed 32-bit id layout (see
    IdLayout), refused with id_layout = micro_batch when they differ from their defaults.
    wave_size: 32 or 64 lanes. tiling: loose (128x128 tiles, waves of one batch group) or tiles
    (8x8 material tiles). vertex_fetch: wave (shading transforms each distinct triangle's
    vertices once per wave: Decima's vertex wave commands) or pixel (three per shaded pixel);
    it sets counts["vertex_invocations"]. vrs: off | fixed | distance | speed | image |
    motion. vrs_rate: the rate of ``fixed`` (1x1, 1x2, 2x1, 2x2). vrs_thresholds (a, b): for
    ``distance`` (world units from the eye to the triangle's centroid), ``speed`` (screen
    pixels per frame of the centroid, from scene.velocity) and ``motion`` (screen pixels per
    frame of the slowest pixel of each 8x8 tile, from the motion vectors against the previous
    frame: object and camera motion; a sequence's first frame sees no camera motion): below a
    1x1, from a to b 2x1 (1x2 for mostly vertical motion), from b 2x2. rate_image: rows of
    rate names stretched over the screen (nearest cell). Each VRS setting is refused away from
    its mode (vrs_rate unless ``fixed``, vrs_thresholds unless ``distance``, ``speed`` or
    ``motion``, rate_image unless ``image``) when it differs from its default."""

    id_layout: str = "micro_batch"
    batch_bits: int = 16
    primitive_bits: int = 7
    instance_bits: int = 9
    wave_size: int = 32
    tiling: str = "loose"
    vertex_fetch: str = "wave"
    vrs: str = "off"
    vrs_rate: str = "2x2"
    vrs_thresholds: tuple = (8.0, 20.0)
    rate_image: tuple = ()

    def __post_init__(self):
        super().__post_init__()
        object.__setattr__(self, "vrs_thresholds", tuple(float(t) for t in self.vrs_thresholds))
        object.__setattr__(self, "rate_image", tuple(tuple(str(r) for r in row)
                                                     for row in self.rate_image))
        self.layout  # validates the bit fields
        check_wave_size(self.wave_size)
        if self.id_layout not in ID_LAYOUTS:
            raise ValueError(f"id_layout must be one of {', '.join(ID_LAYOUTS)}, "
                             f"got {self.id_layout!r}")
        if self.id_layout != "fixed":
            for f in ("batch_bits", "primitive_bits", "instance_bits"):
                if getattr(self, f) != getattr(type(self), f):
                    raise ValueError(f"{f} = {getattr(self, f)} has no effect with id_layout = "
                                     f"{self.id_layout!r} (it sizes the fixed layout); set "
                                     f"id_layout = 'fixed'")
        if self.vertex_fetch not in VERTEX_FETCHES:
            raise ValueError(f"vertex_fetch must be one of {', '.join(VERTEX_FETCHES)}, got "
                             f"{self.vertex_fetch!r}")
        if self.tiling not in TILINGS:
            raise ValueError(f"tiling must be one of {', '.join(TILINGS)}, got {self.tiling!r}")
        if self.vrs not in VRS_MODES:
            raise ValueError(f"vrs must be one of {', '.join(VRS_MODES)}, got {self.vrs!r}")
        if self.vrs_rate not in RATES:
            raise ValueError(f"vrs_rate must be one of {', '.join(RATES)}, got {self.vrs_rate!r}")
        if len(self.vrs_thresholds) != 2 or self.vrs_thresholds[0] > self.vrs_thresholds[1]:
            raise ValueError(f"vrs_thresholds must be (a, b) with a <= b, got {self.vrs_thresholds}")
        if self.vrs == "image":
            if not self.rate_image or len({len(r) for r in self.rate_image}) != 1 \
                    or not self.rate_image[0]:
                raise ValueError("vrs = 'image' needs a non-empty rectangular rate_image")
            bad = sorted({r for row in self.rate_image for r in row} - set(RATES))
            if bad:
                raise ValueError(f"rate_image: unknown rate {bad[0]!r}; rates: {', '.join(RATES)}")
        # Nothing accepted and ignored: a VRS setting of another mode than ``vrs`` is refused.
        cls = type(self)
        if self.vrs != "fixed" and self.vrs_rate != cls.vrs_rate:
            raise ValueError(f"vrs_rate = {self.vrs_rate!r} has no effect with vrs = {self.vrs!r}"
                             f" (it is the rate of vrs = 'fixed')")
        if self.vrs not in SPEED_MODES and self.vrs_thresholds != cls.vrs_thresholds:
            raise ValueError(f"vrs_thresholds = {self.vrs_thresholds} have no effect with vrs = "
                             f"{self.vrs!r} (they apply to vrs = 'distance', 'speed' and "
                             f"'motion')")
        if self.vrs != "image" and self.rate_image:
            raise ValueError(f"rate_image has no effect with vrs = {self.vrs!r} (it is the rate "
                             f"map of vrs = 'image')")

    @property
    def layout(self) -> IdLayout:
        return IdLayout(self.batch_bits, self.primitive_bits, self.instance_bits)


class ShadePlan(NamedTuple):
    """The coarse-pixel plan: ``work`` lists the anchors (the first pixel of each coarse pixel)
    in wave order; ``anchor`` int32[P] is each pixel's anchor, ``is_anchor`` bool[P];
    ``run_starts`` bool[P], True at the first item of each wave run of the sorted list (a
    (tile, batch group) under loose tiling, a (material, rate, tile, wave) under 8x8 tiles),
    ``live_sorted`` bool[P], the items of the sorted list that exist; ``rate`` int32[P]."""

    work: dispatch.WorkList
    anchor: Array
    is_anchor: Array
    run_starts: Array
    live_sorted: Array
    rate: Array


def plan_coarse_pixels(scene, tri, rate, cfg: VisBufferConfig) -> ShadePlan:
    """One shade per (material, rate, aligned block), at its first pixel; the work list in
    wave order (``cfg.tiling``): loose 128x128 tiles, or coarse pixels of one material and
    rate by 8x8 tile of the coarse grid."""
    w, h = cfg.width, cfg.height
    n_pix = w * h
    covered = tri >= 0
    mat = jnp.where(covered, scene.tri_material[jnp.maximum(tri, 0)], BIG).reshape(-1)
    rate = rate.reshape(-1)
    pix = jnp.arange(n_pix, dtype=jnp.int32)
    x, y = pix % w, pix // w
    rw = jnp.asarray(RATE_W, jnp.int32)[rate]
    rh = jnp.asarray(RATE_H, jnp.int32)[rate]
    bx, by = x // rw, y // rh
    n_mat = scene.materials.albedo.shape[0]
    if cfg.vrs == "off":  # every coarse pixel is one pixel: each covered pixel anchors itself
        anchor, is_anchor = pix, covered.reshape(-1)
    else:
        anchor, is_anchor = _coarse_anchors(mat, rate, bx, by, n_mat, w, h)
    n_work = jnp.sum(is_anchor, dtype=jnp.int32)
    if cfg.tiling == "loose":
        work, run_starts, live_sorted = loose_order(is_anchor, mat, x, y, w, h, n_mat)
    else:
        work, run_starts, live_sorted = _tile_order(is_anchor, mat, rate, bx, by, cfg, n_mat)
    return ShadePlan(dispatch.WorkList(work, n_work), anchor, is_anchor, run_starts,
                     live_sorted, rate)


def _coarse_anchors(mat, rate, bx, by, n_mat: int, w: int, h: int) -> tuple[Array, Array]:
    """(each pixel's anchor int32[P], is_anchor bool[P]): the first pixel of each (material,
    rate, aligned block)."""
    n_pix = w * h
    pix = jnp.arange(n_pix, dtype=jnp.int32)
    (m_s, r_s, by_s, bx_s, p_s), _ = lex_sort(
        (mat, rate, by, bx, pix), (n_mat - 1, len(RATES) - 1, h - 1, w - 1, n_pix - 1))
    live = m_s != BIG
    start = segment_starts(m_s, r_s, by_s, bx_s) & live
    anchor_sorted = p_s[first_of_segment_index(start)]
    # p_s is a permutation: unique indices let the scatters be plain stores.
    anchor = jnp.zeros((n_pix,), jnp.int32).at[p_s].set(anchor_sorted, unique_indices=True)
    is_anchor = jnp.zeros((n_pix,), bool).at[p_s].set(start, unique_indices=True)
    return anchor, is_anchor


def _tile_order(is_anchor, mat, rate, bx, by, cfg: VisBufferConfig, n_mat: int):
    """8x8 material tiles: anchors by (material, rate, tile of the coarse grid, wave inside
    the tile). Returns (order, run starts, live entries of the sorted list)."""
    w, h = cfg.width, cfg.height
    pix = jnp.arange(w * h, dtype=jnp.int32)
    tiles_w = -(-w // TILE)
    tile = (by // TILE) * tiles_w + bx // TILE
    sub = ((by % TILE) * TILE + bx % TILE) // cfg.wave_size
    big = lambda a: jnp.where(is_anchor, a, BIG)  # noqa: E731
    n_tiles = tiles_w * -(-h // TILE)
    (wm, wr, wt, wsub), (work,) = lex_sort(
        (big(mat), big(rate), big(tile), big(sub)),
        (n_mat - 1, len(RATES) - 1, n_tiles - 1, TILE * TILE // cfg.wave_size), (pix,))
    live_sorted = wm != BIG
    return work, segment_starts(wm, wr, wt, wsub) & live_sorted, live_sorted


class IdCodec(NamedTuple):
    """The id buffer's encoding under ``cfg.id_layout``: ``micro`` (the micro-batch table) or
    None for the fixed layout; ``rate_bits`` (2 when the rate travels in the id)."""

    micro: MicroBatches | None
    rate_bits: int


def id_codec(scene, cfg: VisBufferConfig) -> IdCodec:
    if cfg.id_layout == "fixed":
        return IdCodec(None, 0)
    return IdCodec(micro_batches(scene.tri_object, scene.tri_material),
                   RATE_BITS if cfg.vrs != "off" else 0)


def encode_ids(scene, codec: IdCodec, tri, rate, cfg: VisBufferConfig):
    """int32 triangles (-1 empty) and rate codes -> (uint32 ids, overflow count)."""
    if codec.micro is None:
        return encode(scene, tri, cfg.layout)
    return micro_batch.pack(codec.micro, tri, rate, codec.rate_bits)


def decode_ids(scene, codec: IdCodec, ids, rate, cfg: VisBufferConfig):
    """uint32 ids -> (int32 triangles, -1 empty; rate codes: read from the id where it travels
    there, else ``rate`` as given)."""
    if codec.micro is None:
        return decode(scene, ids, cfg.layout), rate
    tri, id_rate = micro_batch.unpack(codec.micro, ids, codec.rate_bits)
    return tri, (id_rate if codec.rate_bits else rate)


def init(scene, static, camera, cfg: VisBufferConfig):
    """The state: the previous frame's camera (the first frame's own: no camera motion yet),
    for the motion vectors of ``vrs = "motion"``."""
    return camera


@register("visbuffer", VisBufferConfig, init=init)
def step(scene, static, prev_camera, camera, t, cfg: VisBufferConfig):
    """Visibility buffer: packed 32-bit ids, shading from the id in loose tiles, VRS."""
    return frame(scene, camera, t, prev_camera, cfg), camera


def frame(scene, camera, t, prev_camera, cfg: VisBufferConfig) -> Frame:
    """Frame ``t``; ``prev_camera`` (with the scene at t - 1) gives the motion vectors under
    ``vrs = "motion"`` and is unused otherwise."""
    w, h = cfg.width, cfg.height
    codec = id_codec(scene, cfg)
    with jax.named_scope("visibility"):
        previous = (Previous(positions_at(scene, t - 1), prev_camera) if cfg.vrs == "motion"
                    else None)
        vis = visibility(scene, camera, cfg, previous=previous)
        rate = pixel_rates(scene, camera, cfg, vis)  # the raster pass knows the rate
        ids, id_overflow = encode_ids(scene, codec, vis.tri_id, rate, cfg)  # what it writes
    with jax.named_scope("classify"):
        tri, rate = decode_ids(scene, codec, ids, rate, cfg)  # classification reads the ids
        plan = plan_coarse_pixels(scene, tri, rate, cfg)
    with jax.named_scope("shade"):
        clip = clip_vertices(scene, camera, cfg)
        ids_flat = ids.reshape(-1)

        def fn(items, live_lanes):
            t, _ = decode_ids(scene, codec, ids_flat[items], None, cfg)  # shading from the id
            pts = points_at(scene, camera, clip, cfg, jnp.where(live_lanes, t, -1), items)
            return shade(pts, scene)

        out, work = dispatch.run(plan.work, fn, jnp.zeros((w * h, 3), jnp.float32), cfg.chunk)
    covered = tri >= 0
    with jax.named_scope("broadcast"):
        image = jnp.where(covered.reshape(-1)[:, None], out[plan.anchor], 0.0).reshape(h, w, 3)
        overflow = id_overflow + vis.counts["overflow"]
    image, blended = transparent_pass(scene, camera, image, vis.depth, cfg)
    counts = merge_counts(_counts(vis, plan, work, covered, id_overflow, overflow, cfg), blended)
    counts.update(shading_vertex_counts(scene, plan, tri, work, cfg))
    image = poison_on_overflow(image, counts["overflow"])
    aux = {"ids": ids, "rate": plan.rate.reshape(h, w),
           "shade_count": plan.is_anchor.astype(jnp.int32).reshape(h, w)}
    return Frame(image, counts, share_visibility(aux, vis, cfg))


def shading_vertex_counts(scene, plan: ShadePlan, tri, work: dispatch.WorkList,
                          cfg: VisBufferConfig) -> dict:
    """The id pass transforms every vertex (positions only); shading fetches and transforms
    a triangle's three vertices per shaded pixel, or per distinct triangle of each wave."""
    if cfg.vertex_fetch == "pixel":
        shaded = 3 * work.invocations
    else:
        tri_sorted = tri.reshape(-1)[plan.work.items]
        shaded = 3 * wave_triangles(plan.run_starts, plan.live_sorted, tri_sorted,
                                    cfg.wave_size, scene.faces.shape[0])
    return vertex_counts(scene, full_passes=0, position_passes=1, shaded_vertices=shaded)


def _counts(vis, plan: ShadePlan, work: dispatch.WorkList, covered, id_overflow, overflow,
            cfg) -> dict:
    inv = work.invocations
    waves = command_counts(plan.run_starts, plan.live_sorted, cfg.wave_size, inv, cfg.tiling)
    n_cov = jnp.sum(covered, dtype=jnp.int32)
    id_bytes = 4
    written = n_cov * (id_bytes + 4)  # id + depth
    # The classification pass reads every id and writes the commands; shading reads the
    # commands and its own ids.
    commands = waves["pixel_command_bytes"] + waves["wave_command_bytes"]
    read = cfg.width * cfg.height * id_bytes + inv * id_bytes
    return make_counts(
        shade_invocations=inv, covered_pixels=n_cov, **waves,
        bytes_intermediate=written + read + 2 * commands, id_overflow=id_overflow,
        overflow=overflow, alpha_invocations=vis.counts["alpha_invocations"])


render = REGISTRY["visbuffer"].render  # the compiled, overflow-checked entry
render_sequence = REGISTRY["visbuffer"].render_sequence
