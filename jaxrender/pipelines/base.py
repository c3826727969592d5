"""What every pipeline shares: the config base, exact (alpha-tested) visibility, surface
points from a triangle id at any pixel, shading of a visibility buffer over a compacted work
list, and the standard counts of a Frame.

A pipeline registers its ``step`` (or a stateless ``frame``) with the registry
(``registry.register`` / ``register_frame``); ``pipelines.program`` compiles and runs it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import jax
import jax.numpy as jnp

from jaxrender.pipelines.dispatch import DEFAULT_CHUNK, dispatch, shade_pixels
from jaxrender.pipelines.registry import RenderConfig
from jaxrender.raster import samples as sample_patterns
from jaxrender.raster.fragments import Fragments, fragments_jit
from jaxrender.raster.rasterize import (default_clip_capacity, default_work_capacity,
                                        rasterize_traced)
from jaxrender.raster.resolve import barycentrics
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene.camera import Camera, world_to_clip
from jaxrender.scene.scene import Scene
from jaxrender.shading import alpha_test, shade, surface_points
from jaxrender.types import Array, Frame, SurfacePoints, VisBuffer

# Keys present in every Frame's counts (0 where a pipeline has no such notion).
INT_COUNTS = ("shade_invocations", "helper_lanes", "covered_pixels", "waves",
              "bytes_intermediate")
FLOAT_COUNTS = ("overshading", "lane_utilization")
COUNT_KEYS = INT_COUNTS + FLOAT_COUNTS


@dataclass(frozen=True)
class PipelineConfig(RenderConfig):
    """Settings shared by the raster-based pipelines.

    chunk: lanes per shading dispatch chunk (the DispatchIndirect group size of the work list);
        0 (the default) sizes it to the work list (``dispatch.auto_chunk``: about eight
        chunks for a full screen).
    cull_backfaces: drop back-facing triangles in the rasterizer.
    fragment_capacity: size of the fragment list per sample (0 = 4 x width x height); a frame
        with more fragments reports ``overflow`` and, called eagerly, raises OverflowError.
    """

    chunk: int = DEFAULT_CHUNK
    cull_backfaces: bool = False
    fragment_capacity: int = 0

    OUTPUT_NEUTRAL: ClassVar[tuple[str, ...]] = ("chunk", "fragment_capacity")

    def __post_init__(self):
        if int(self.chunk) < 0:
            raise ValueError(f"chunk must be >= 0 (0: automatic), got {self.chunk}")
        if int(self.fragment_capacity) < 0:
            raise ValueError(f"fragment_capacity must be >= 0, got {self.fragment_capacity}")

    @property
    def capacity(self) -> int:
        return int(self.fragment_capacity or 4 * self.width * self.height)

    def overflow_hint(self) -> str:
        return (f"fragments past fragment_capacity={self.capacity}, or visibility ids that do "
                f"not fit their bit fields; raise fragment_capacity (see the Frame counts)")


def make_counts(**values) -> dict:
    """The standard counts dict: every key of COUNT_KEYS (0 when not given) plus extras.
    ``overshading`` defaults to shade_invocations / covered_pixels."""
    out = {}
    for k in INT_COUNTS:
        out[k] = jnp.asarray(values.pop(k, 0)).astype(jnp.int32)
    inv = out["shade_invocations"].astype(jnp.float32)
    cov = out["covered_pixels"].astype(jnp.float32)
    default_over = inv / jnp.maximum(cov, 1.0)
    out["overshading"] = jnp.asarray(values.pop("overshading", default_over)).astype(jnp.float32)
    out["lane_utilization"] = jnp.asarray(values.pop("lane_utilization", 0.0)).astype(jnp.float32)
    for k, v in values.items():
        v = jnp.asarray(v)
        out[k] = v.astype(jnp.float32 if jnp.issubdtype(v.dtype, jnp.floating) else jnp.int32)
    return out


def poison_on_overflow(image: Array, overflow: Array) -> Array:
    """NaN everywhere when something overflowed: a frame with missing work must look broken."""
    return jnp.where(overflow > 0, jnp.float32(jnp.nan), image)


def clip_vertices(scene: Scene, camera: Camera, cfg) -> Array:
    return world_to_clip(scene.positions, camera, cfg.width / cfg.height)


# ---------------------------------------------------------------- raster entry points
# The public raster entries validate their inputs with NumPy and so cannot take the scene's
# traced face array inside a jitted pipeline; these call the same jitted cores with the same
# argument preparation (the validation is the scene loader's job here).


def raster_fragments(clip: Array, faces: Array, cfg, *, cull_backfaces: bool = False,
                     sample_offset=(0.5, 0.5)) -> Fragments:
    """``raster.fragments`` of clip-space vertices for a traced scene, capacity ``cfg.capacity``."""
    (offset,) = sample_patterns.to_fixed(sample_patterns.validate([sample_offset]), SUBPIXEL_BITS)
    n_tris = faces.shape[0]
    return fragments_jit(
        clip, faces, width=cfg.width, height=cfg.height, capacity=cfg.capacity,
        cull_backfaces=bool(cull_backfaces), offset=offset,
        work_capacity=default_work_capacity(n_tris, cfg.width, cfg.height),
        clip_capacity=default_clip_capacity(n_tris))


def raster_visbuffer(clip: Array, faces: Array, cfg, *, cull_backfaces: bool = False,
                     sample_offsets=None) -> VisBuffer:
    """``raster.rasterize_clip`` for a traced scene: (H, W), or (S, H, W) for S > 1 offsets."""
    offsets = sample_patterns.validate(sample_offsets or sample_patterns.CENTER)
    n_tris = faces.shape[0]
    return rasterize_traced(
        clip, faces, width=cfg.width, height=cfg.height, cull_backfaces=bool(cull_backfaces),
        offsets=sample_patterns.to_fixed(offsets, SUBPIXEL_BITS),
        work_capacity=default_work_capacity(n_tris, cfg.width, cfg.height),
        clip_capacity=default_clip_capacity(n_tris))


# ---------------------------------------------------------------- barycentrics at any pixel


def pixel_barycentrics(clip: Array, faces: Array, tri: Array, px: Array, py: Array,
                       width: int, height: int, offset=(0.5, 0.5)):
    """Perspective-correct barycentrics of triangle ``tri`` int32[N] at the sample point
    (px + ox, py + oy) of pixels px, py int32[N], and their d/dx, d/dy (per pixel right / down).

    The same homogeneous (Olano-Greer) formulation as the rasterizer's resolve, for a flat list
    of (triangle, pixel) pairs: the point may lie outside the triangle (quad helper lanes), the
    barycentrics are then extrapolated, unclamped. Returns three float32[N, 3].
    """
    verts = clip[faces[jnp.maximum(tri, 0)]]  # [N, 3, 4]
    c = jnp.stack([verts[..., 0], verts[..., 1], verts[..., 3]], axis=-1)  # [N, 3, 3]
    rows = jnp.stack([jnp.cross(c[:, 1], c[:, 2]), jnp.cross(c[:, 2], c[:, 0]),
                      jnp.cross(c[:, 0], c[:, 1])], axis=-2)
    scale = jnp.max(jnp.abs(rows), axis=(-2, -1), keepdims=True)
    rows = rows / jnp.where(scale > 0, scale, 1.0)
    u = (px.astype(jnp.float32) + offset[0]) * (2.0 / width) - 1.0
    v = 1.0 - (py.astype(jnp.float32) + offset[1]) * (2.0 / height)
    e = rows[..., 0] * u[:, None] + rows[..., 1] * v[:, None] + rows[..., 2]
    s = jnp.sum(e, axis=-1, keepdims=True)
    ok = (tri >= 0)[:, None] & (s != 0.0)
    s = jnp.where(ok, s, 1.0)
    b = e / s
    db_du = (rows[..., 0] - b * jnp.sum(rows[..., 0], axis=-1, keepdims=True)) / s
    db_dv = (rows[..., 1] - b * jnp.sum(rows[..., 1], axis=-1, keepdims=True)) / s
    inside = jnp.all(b >= 0.0, axis=-1, keepdims=True)
    # Inside the triangle clamp a rounding error away, as resolve does; outside extrapolate.
    bc = jnp.clip(b, 0.0, 1.0)
    bc = bc / jnp.maximum(jnp.sum(bc, axis=-1, keepdims=True), 1e-30)
    b = jnp.where(inside, bc, b)
    zero = jnp.zeros_like(b)
    third = jnp.full_like(b, 1.0 / 3.0)
    bary = jnp.where(ok, b, jnp.where((tri >= 0)[:, None], third, zero))
    ddx = jnp.where(ok, db_du * (2.0 / width), zero)
    ddy = jnp.where(ok, db_dv * (-2.0 / height), zero)
    return bary, ddx, ddy


def points_at(scene: Scene, camera: Camera, clip: Array, cfg, tri: Array, pixel: Array,
              offset=(0.5, 0.5)) -> SurfacePoints:
    """SurfacePoints of triangles ``tri`` at flat pixel indices ``pixel`` (y * W + x)."""
    px, py = pixel % cfg.width, pixel // cfg.width
    return points_at_xy(scene, camera, clip, cfg, tri, px, py, offset)


def points_at_xy(scene, camera, clip, cfg, tri, px, py, offset=(0.5, 0.5)) -> SurfacePoints:
    b, dx, dy = pixel_barycentrics(clip, scene.faces, tri, px, py, cfg.width, cfg.height, offset)
    return surface_points(scene, camera, tri, b, dx, dy)


def points_from_vis(scene: Scene, camera: Camera, vis: VisBuffer, items: Array) -> SurfacePoints:
    """SurfacePoints of the flat pixel indices ``items`` of a single-sample VisBuffer."""
    flat = lambda a: a.reshape((-1,) + a.shape[2:])  # noqa: E731
    return surface_points(scene, camera, flat(vis.tri_id)[items], flat(vis.bary)[items],
                          flat(vis.dbary_dx)[items], flat(vis.dbary_dy)[items])


def shade_vis_pixels(scene: Scene, camera: Camera, vis: VisBuffer, active: Array,
                     chunk: int = DEFAULT_CHUNK, out: Array | None = None):
    """Shade the pixels flagged in bool[H, W] from a single-sample VisBuffer through the chunked
    dispatch. Returns (image float32[H, W, 3], dispatch counts: invocations, lanes, chunks)."""
    h, w = active.shape
    if out is None:
        out = jnp.zeros((h * w, 3), jnp.float32)
    else:
        out = out.reshape(h * w, 3)
    img, counts = shade_pixels(
        active.reshape(-1),
        lambda items: points_from_vis(scene, camera, vis, items),
        lambda pts: shade(pts, scene),
        out, chunk,
    )
    return img.reshape(h, w, 3), counts


# ---------------------------------------------------------------- exact visibility


def visibility(scene: Scene, camera: Camera, cfg, sample_offsets=None) -> VisBuffer:
    """The nearest surviving surface at each pixel (or sample): a VisBuffer of shape (H, W), or
    (S, H, W) for S > 1 ``sample_offsets``.

    Without the alpha-test effect this is the rasterizer's own visibility. With it, every
    fragment is listed; fragments of alpha-tested materials that could be visible (not behind
    the nearest opaque fragment) are alpha-tested at their sample point through the chunked
    dispatch; the nearest survivor (lowest triangle id on ties) wins, as the rasterizer's depth
    key orders them. Counts add ``alpha_invocations`` and ``overflow`` (fragments past
    ``cfg.capacity``).
    """
    offsets = sample_patterns.validate(sample_offsets or sample_patterns.CENTER)
    cull = bool(getattr(cfg, "cull_backfaces", False))
    if not scene.effects.alpha_test:
        vis = raster_visbuffer(clip_vertices(scene, camera, cfg), scene.faces, cfg,
                               cull_backfaces=cull, sample_offsets=offsets)
        return VisBuffer(vis.tri_id, vis.depth, vis.bary, vis.dbary_dx, vis.dbary_dy,
                         dict(vis.counts, alpha_invocations=jnp.int32(0), overflow=jnp.int32(0)))
    clip = clip_vertices(scene, camera, cfg)
    per = [_alpha_visibility(scene, camera, clip, cfg, off, cull) for off in offsets]
    if len(per) == 1:
        return per[0]
    stack = lambda *a: jnp.stack(a)  # noqa: E731
    counts = {k: sum(v.counts[k] for v in per) for k in per[0].counts}
    return VisBuffer(*(stack(*(getattr(v, f) for v in per))
                       for f in ("tri_id", "depth", "bary", "dbary_dx", "dbary_dy")), counts)


def is_alpha_tested(scene: Scene, tri: Array) -> Array:
    """bool[N]: the triangle's material is alpha-tested (always False without the effect)."""
    if not scene.effects.alpha_test:
        return jnp.zeros(tri.shape, bool)
    return scene.materials.alpha_tested[scene.tri_material[jnp.maximum(tri, 0)]] & (tri >= 0)


def _alpha_visibility(scene, camera, clip, cfg, offset, cull) -> VisBuffer:
    w, h, cap = cfg.width, cfg.height, cfg.capacity
    n_pix = w * h
    fr = raster_fragments(clip, scene.faces, cfg, cull_backfaces=cull, sample_offset=offset)
    pix = jnp.where(fr.valid, fr.pixel, n_pix)
    tested = is_alpha_tested(scene, fr.tri) & fr.valid
    inf = float("inf")
    z_opaque = jnp.full((n_pix,), inf).at[pix].min(
        jnp.where(fr.valid & ~tested, fr.depth, inf), mode="drop")
    candidate = tested & (fr.depth <= z_opaque.at[pix].get(mode="fill", fill_value=0.0))
    with jax.named_scope("alpha_test"):
        keep_f, ac = dispatch_points(
            candidate,
            lambda items: points_at(scene, camera, clip, cfg, fr.tri[items], fr.pixel[items],
                                    offset),
            lambda pts: alpha_test(pts, scene).astype(jnp.float32),
            jnp.zeros((cap,), jnp.float32), cfg.chunk)
    keep = fr.valid & (~tested | (keep_f > 0.5))
    zkeep = jnp.where(keep, fr.depth, inf)
    zbuf = jnp.full((n_pix,), inf).at[pix].min(zkeep, mode="drop")
    big = jnp.int32(2**31 - 1)
    win = keep & (fr.depth == zbuf.at[pix].get(mode="fill", fill_value=0.0))
    tri = jnp.full((n_pix,), big).at[pix].min(jnp.where(win, fr.tri, big), mode="drop")
    tri = jnp.where(tri == big, -1, tri).reshape(h, w)
    depth = jnp.where(jnp.isinf(zbuf), 1.0, zbuf).reshape(h, w)
    bary, ddx, ddy = barycentrics(tri, clip, scene.faces, w, h,
                                  jnp.asarray(offset, jnp.float32))
    counts = {"fragments": fr.count, "alpha_invocations": ac["invocations"],
              "overflow": fr.overflowed.astype(jnp.int32)}
    return VisBuffer(tri, depth, bary, ddx, ddy, counts)


def dispatch_points(active: Array, points_of, fn, out: Array, chunk: int):
    """``fn(points)`` over the compacted True entries of ``active`` (any per-point shader, e.g.
    the alpha test), written into ``out``; the chunked dispatch of ``shade_pixels``."""
    return shade_pixels(active, points_of, fn, out, chunk)


__all__ = [
    "COUNT_KEYS", "PipelineConfig", "clip_vertices", "dispatch", "dispatch_points",
    "is_alpha_tested", "make_counts", "pixel_barycentrics", "points_at",
    "points_at_xy", "points_from_vis", "poison_on_overflow", "raster_fragments",
    "raster_visbuffer", "shade_vis_pixels", "visibility",
]
