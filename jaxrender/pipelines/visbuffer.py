"""Visibility-buffer shading (Decima-style): the raster pass writes a 32-bit packed id per
pixel; shading decodes the id, fetches the triangle, computes perspective-correct barycentrics
and their analytic derivatives at the pixel, and shades. No quads, so no helper lanes.

Shading work is classified into 8x8 tiles per material and packed into waves of 32 or 64 lanes;
the work list is ordered by (material, rate, tile, wave), and the wave counts are read off it.
Software VRS: each pixel gets a rate 1x1, 1x2, 2x1 or 2x2 (width x height) from a per-triangle
rule (view distance or screen-space speed) or a rate image; the pixels of one material and rate
in one aligned coarse block share a single shade at the block's first pixel, broadcast to them.
Waves of coarse pixels are formed on the coarse grid of their rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.base import PipelineConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.quads import BIG, first_of_segment_index, segment_starts
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.pipelines.visibility import clip_vertices, points_at, visibility
from jaxrender.pipelines.waves import TILE, check_wave_size, count_waves, segment_lanes
from jaxrender.scene.camera import world_to_clip
from jaxrender.shading import shade
from jaxrender.sorting import lex_sort
from jaxrender.types import Array, Frame

EMPTY_ID = 0xFFFFFFFF
RATES = ("1x1", "1x2", "2x1", "2x2")  # width x height, as D3D12_SHADING_RATE_AxB
RATE_W = (1, 1, 2, 2)
RATE_H = (1, 2, 1, 2)
VRS_MODES = ("off", "fixed", "distance", "speed", "image")


@dataclass(frozen=True)
class IdLayout:
    """Bit fields of the 32-bit visibility id, most significant first: micro batch, primitive
    (inside its batch), instance. A triangle ``t`` of object (instance) ``i`` whose first
    triangle is ``f`` has local index ``t - f = batch * 2^primitive_bits + primitive``."""

    batch_bits: int = 16
    primitive_bits: int = 7
    instance_bits: int = 9

    def __post_init__(self):
        bits = (self.batch_bits, self.primitive_bits, self.instance_bits)
        if min(bits) < 0 or sum(bits) > 32:
            raise ValueError(f"id layout {bits}: fields must be >= 0 and sum to <= 32 bits")

    def pack(self, batch, prim, inst):
        """(uint32 ids, bool overflow) for int32 arrays; an overflowing field, or an id equal to
        the empty value 0xFFFFFFFF, sets overflow."""
        batch, prim, inst = (jnp.asarray(a, jnp.int32) for a in (batch, prim, inst))
        over = jnp.zeros(batch.shape, bool)
        for v, bits in ((batch, self.batch_bits), (prim, self.primitive_bits),
                        (inst, self.instance_bits)):
            over = over | (v < 0)
            if bits < 31:  # an int32 cannot exceed a wider field
                over = over | (v >= (1 << bits))
        u = lambda a: a.astype(jnp.uint32)  # noqa: E731
        pb, ib = self.primitive_bits, self.instance_bits
        ids = (u(batch) << (pb + ib)) | (u(prim) << ib) | u(inst)
        if self.batch_bits + pb + ib == 32:  # else the all-ones id is unreachable
            over = over | (ids == jnp.uint32(EMPTY_ID))
        return ids, over

    def unpack(self, ids):
        """uint32 ids -> (batch, primitive, instance) int32."""
        ids = jnp.asarray(ids, jnp.uint32)
        pb, ib = self.primitive_bits, self.instance_bits
        mask = lambda b: jnp.uint32((1 << b) - 1)  # noqa: E731
        inst = ids & mask(ib)
        prim = (ids >> ib) & mask(pb)
        batch = (ids >> (pb + ib)) & mask(self.batch_bits)
        return batch.astype(jnp.int32), prim.astype(jnp.int32), inst.astype(jnp.int32)


def pack_ids(layout: IdLayout, batch, prim, inst):
    """Eager packing that refuses overflow: raises OverflowError naming the field."""
    b, p, i = (np.asarray(a) for a in (batch, prim, inst))
    for name, v, bits in (("batch", b, layout.batch_bits), ("primitive", p, layout.primitive_bits),
                          ("instance", i, layout.instance_bits)):
        if v.size and (v.min() < 0 or v.max() >= (1 << bits)):
            raise OverflowError(f"visibility id: {name} value {int(v.max())} does not fit in "
                                f"{bits} bits")
    ids, over = layout.pack(b, p, i)
    if bool(jnp.any(over)):
        raise OverflowError("visibility id: the packed id equals the reserved empty id")
    return ids


@dataclass(frozen=True)
class VisBufferConfig(PipelineConfig):
    """batch_bits / primitive_bits / instance_bits: the 32-bit id layout (see IdLayout).
    wave_size: 32 or 64 lanes. vrs: off | fixed | distance | speed | image. vrs_rate: the rate
    of ``fixed`` (1x1, 1x2, 2x1, 2x2). vrs_thresholds (a, b): for ``distance`` (world units from
    the eye to the triangle's centroid) and ``speed`` (screen pixels per frame of the centroid,
    from scene.velocity): below a 1x1, from a to b 2x1 (1x2 for mostly vertical motion), from b
    2x2. rate_image: rows of rate names stretched over the screen (nearest cell). Each VRS
    setting is refused away from its mode (vrs_rate unless ``fixed``, vrs_thresholds unless
    ``distance`` or ``speed``, rate_image unless ``image``) when it differs from its default."""

    batch_bits: int = 16
    primitive_bits: int = 7
    instance_bits: int = 9
    wave_size: int = 32
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
        if self.vrs not in ("distance", "speed") and self.vrs_thresholds != cls.vrs_thresholds:
            raise ValueError(f"vrs_thresholds = {self.vrs_thresholds} have no effect with vrs = "
                             f"{self.vrs!r} (they apply to vrs = 'distance' and 'speed')")
        if self.vrs != "image" and self.rate_image:
            raise ValueError(f"rate_image has no effect with vrs = {self.vrs!r} (it is the rate "
                             f"map of vrs = 'image')")

    @property
    def layout(self) -> IdLayout:
        return IdLayout(self.batch_bits, self.primitive_bits, self.instance_bits)


def object_first_triangle(scene) -> jax.Array:
    """int32[T]: entry i is the first triangle of object i (objects are contiguous)."""
    t = scene.faces.shape[0]
    return jnp.full((t,), BIG, jnp.int32).at[scene.tri_object].min(
        jnp.arange(t, dtype=jnp.int32), mode="drop")


def encode(scene, tri, layout: IdLayout):
    """int32 triangle ids (-1 = empty) -> (uint32 packed ids, overflow count)."""
    first = object_first_triangle(scene)
    t = jnp.maximum(tri, 0)
    inst = scene.tri_object[t]
    local = t - first[inst]
    ids, over = layout.pack(local >> layout.primitive_bits,
                            local & ((1 << layout.primitive_bits) - 1), inst)
    covered = tri >= 0
    return (jnp.where(covered, ids, jnp.uint32(EMPTY_ID)),
            jnp.sum(over & covered, dtype=jnp.int32))


def decode(scene, ids, layout: IdLayout):
    """uint32 packed ids -> int32 triangle ids (-1 for the empty id)."""
    batch, prim, inst = layout.unpack(ids)
    first = object_first_triangle(scene)
    tri = first[jnp.minimum(inst, first.shape[0] - 1)] + (batch << layout.primitive_bits) + prim
    return jnp.where(ids == jnp.uint32(EMPTY_ID), -1, tri)


def triangle_rates(scene, camera, cfg) -> jax.Array:
    """int32[T] rate code (index into RATES) of every triangle under cfg.vrs."""
    n = scene.faces.shape[0]
    a, b = cfg.vrs_thresholds
    if cfg.vrs == "fixed":
        return jnp.full((n,), RATES.index(cfg.vrs_rate), jnp.int32)
    centroid = jnp.mean(scene.positions[scene.faces], axis=1)
    if cfg.vrs == "distance":
        d = jnp.sqrt(jnp.sum(jnp.square(centroid - camera.eye[None, :]), axis=-1))
        return jnp.where(d < a, 0, jnp.where(d < b, 2, 3)).astype(jnp.int32)
    if cfg.vrs == "speed":
        vel = jnp.mean(scene.velocity[scene.faces], axis=1)
        aspect = cfg.width / cfg.height
        c0 = world_to_clip(centroid, camera, aspect)
        c1 = world_to_clip(centroid + vel, camera, aspect)
        win = lambda c: c[:, :2] / jnp.maximum(c[:, 3:4], 1e-6)  # noqa: E731
        dd = (win(c1) - win(c0)) * (jnp.asarray([cfg.width, cfg.height], jnp.float32) * 0.5)
        s = jnp.sqrt(jnp.sum(dd * dd, axis=-1))
        mid = jnp.where(jnp.abs(dd[:, 0]) >= jnp.abs(dd[:, 1]), 2, 1)
        return jnp.where(s < a, 0, jnp.where(s < b, mid, 3)).astype(jnp.int32)
    return jnp.zeros((n,), jnp.int32)


def pixel_rates(scene, camera, cfg, tri) -> jax.Array:
    """int32[H, W] rate code of every pixel (0 = 1x1 where VRS is off)."""
    h, w = cfg.height, cfg.width
    if cfg.vrs == "off":
        return jnp.zeros((h, w), jnp.int32)
    if cfg.vrs == "image":
        grid = np.array([[RATES.index(r) for r in row] for row in cfg.rate_image], np.int32)
        rows = np.arange(h) * grid.shape[0] // h
        cols = np.arange(w) * grid.shape[1] // w
        return jnp.asarray(grid[rows[:, None], cols[None, :]])
    return triangle_rates(scene, camera, cfg)[jnp.maximum(tri, 0)]


class ShadePlan(NamedTuple):
    """The coarse-pixel plan: ``work`` lists the anchors (the first pixel of each coarse pixel)
    ordered by (material, rate, tile, wave); ``anchor`` int32[P] is each pixel's anchor,
    ``is_anchor`` bool[P]; ``wave_lanes`` int32[P], the lanes of each wave group of the sorted
    list; ``rate`` int32[P]."""

    work: dispatch.WorkList
    anchor: Array
    is_anchor: Array
    wave_lanes: Array
    rate: Array


def plan_coarse_pixels(scene, camera, tri, cfg: VisBufferConfig) -> ShadePlan:
    """One shade per (material, rate, aligned block), at its first pixel; the work list in
    wave order: coarse pixels of one material and rate, by 8x8 tile of the coarse grid."""
    w, h = cfg.width, cfg.height
    n_pix = w * h
    covered = tri >= 0
    mat = jnp.where(covered, scene.tri_material[jnp.maximum(tri, 0)], BIG).reshape(-1)
    rate = pixel_rates(scene, camera, cfg, tri).reshape(-1)
    pix = jnp.arange(n_pix, dtype=jnp.int32)
    x, y = pix % w, pix // w
    rw = jnp.asarray(RATE_W, jnp.int32)[rate]
    rh = jnp.asarray(RATE_H, jnp.int32)[rate]
    bx, by = x // rw, y // rh
    n_mat = scene.materials.albedo.shape[0]
    n_rates = len(RATES)
    (m_s, r_s, by_s, bx_s, p_s), _ = lex_sort(
        (mat, rate, by, bx, pix), (n_mat - 1, n_rates - 1, h - 1, w - 1, n_pix - 1))
    live = m_s != BIG
    start = segment_starts(m_s, r_s, by_s, bx_s) & live
    anchor_sorted = p_s[first_of_segment_index(start)]
    # p_s is a permutation: unique indices let the scatters be plain stores.
    anchor = jnp.zeros((n_pix,), jnp.int32).at[p_s].set(anchor_sorted, unique_indices=True)
    is_anchor = jnp.zeros((n_pix,), bool).at[p_s].set(start, unique_indices=True)
    tiles_w = -(-w // TILE)
    tile = (by // TILE) * tiles_w + bx // TILE
    sub = ((by % TILE) * TILE + bx % TILE) // cfg.wave_size
    big = lambda a: jnp.where(is_anchor, a, BIG)  # noqa: E731
    n_tiles = tiles_w * -(-h // TILE)
    (wm, wr, wt, wsub), (work,) = lex_sort(
        (big(mat), big(rate), big(tile), big(sub)),
        (n_mat - 1, n_rates - 1, n_tiles - 1, TILE * TILE // cfg.wave_size), (pix,))
    n_work = jnp.sum(is_anchor, dtype=jnp.int32)
    wave_lanes = segment_lanes(segment_starts(wm, wr, wt, wsub), wm != BIG)
    return ShadePlan(dispatch.WorkList(work, n_work), anchor, is_anchor, wave_lanes, rate)


@register_frame("visbuffer", VisBufferConfig)
def frame(scene, camera, cfg: VisBufferConfig) -> Frame:
    """Visibility buffer: packed 32-bit ids, shading from the id in material tiles/waves, VRS."""
    w, h = cfg.width, cfg.height
    layout = cfg.layout
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg)
        ids, id_overflow = encode(scene, vis.tri_id, layout)  # the buffer the raster pass writes
    with jax.named_scope("classify"):
        tri = decode(scene, ids, layout)  # the classification pass reads the ids
        plan = plan_coarse_pixels(scene, camera, tri, cfg)
    with jax.named_scope("shade"):
        clip = clip_vertices(scene, camera, cfg)
        ids_flat = ids.reshape(-1)

        def fn(items, live_lanes):
            t = decode(scene, ids_flat[items], layout)  # shading from the id
            pts = points_at(scene, camera, clip, cfg, jnp.where(live_lanes, t, -1), items)
            return shade(pts, scene)

        out, work = dispatch.run(plan.work, fn, jnp.zeros((w * h, 3), jnp.float32), cfg.chunk)
    covered = tri >= 0
    with jax.named_scope("broadcast"):
        image = jnp.where(covered.reshape(-1)[:, None], out[plan.anchor], 0.0).reshape(h, w, 3)
        overflow = id_overflow + vis.counts["overflow"]
        image = poison_on_overflow(image, overflow)
    counts = _counts(vis, plan, work, covered, id_overflow, overflow, cfg)
    aux = {"ids": ids, "rate": plan.rate.reshape(h, w),
           "shade_count": plan.is_anchor.astype(jnp.int32).reshape(h, w)}
    return Frame(image, counts, aux)


def _counts(vis, plan: ShadePlan, work: dispatch.WorkList, covered, id_overflow, overflow,
            cfg) -> dict:
    inv = work.invocations
    waves, util = count_waves(plan.wave_lanes, cfg.wave_size, inv)
    n_cov = jnp.sum(covered, dtype=jnp.int32)
    id_bytes = 4
    written = n_cov * (id_bytes + 4)  # id + depth
    # The classification pass reads every id, shading its own.
    read = cfg.width * cfg.height * id_bytes + inv * id_bytes
    return make_counts(
        shade_invocations=inv, covered_pixels=n_cov, waves=waves, lane_utilization=util,
        bytes_intermediate=written + read, id_overflow=id_overflow,
        overflow=overflow, alpha_invocations=vis.counts["alpha_invocations"])


render = REGISTRY["visbuffer"].render  # the compiled, overflow-checked entry
