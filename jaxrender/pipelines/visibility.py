"""Visibility for the pipelines: the rasterizer's entries for a traced scene, exact alpha-tested
visibility, and surface points of (triangle, pixel) pairs or of a visibility buffer's pixels.

The public raster entries validate their inputs with NumPy and so cannot take the scene's
traced face array inside a jitted pipeline; these call the same jitted cores with the same
argument preparation (the validation is the scene loader's job here).
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
import jaxrender.raster.samples as sample_patterns
from jaxrender.raster.fragments import Fragments, fragments_jit
from jaxrender.raster.motion import motion_vectors
from jaxrender.raster.rasterize import (default_clip_capacity, default_work_capacity,
                                        rasterize_traced)
from jaxrender.raster.resolve import barycentrics, pair_barycentrics
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene.camera import Camera, world_to_clip
from jaxrender.scene.scene import Scene
from jaxrender.shading import alpha_test, surface_points
from jaxrender.types import Array, SurfacePoints, VisBuffer


def clip_vertices(scene: Scene, camera: Camera, cfg) -> Array:
    return world_to_clip(scene.positions, camera, cfg.width / cfg.height)


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


def points_at(scene: Scene, camera: Camera, clip: Array, cfg, tri: Array, pixel: Array,
              offset=(0.5, 0.5)) -> SurfacePoints:
    """SurfacePoints of triangles ``tri`` at flat pixel indices ``pixel`` (y * W + x)."""
    px, py = pixel % cfg.width, pixel // cfg.width
    return points_at_xy(scene, camera, clip, cfg, tri, px, py, offset)


def points_at_xy(scene, camera, clip, cfg, tri, px, py, offset=(0.5, 0.5)) -> SurfacePoints:
    b, dx, dy = pair_barycentrics(clip, scene.faces, tri, px, py, cfg.width, cfg.height, offset)
    return surface_points(scene, camera, tri, b, dx, dy)


def points_from_vis(scene: Scene, camera: Camera, vis: VisBuffer, items: Array) -> SurfacePoints:
    """SurfacePoints of the flat pixel indices ``items`` of a single-sample VisBuffer."""
    flat = lambda a: a.reshape((-1,) + a.shape[2:])  # noqa: E731
    return surface_points(scene, camera, flat(vis.tri_id)[items], flat(vis.bary)[items],
                          flat(vis.dbary_dx)[items], flat(vis.dbary_dy)[items])


class Previous(NamedTuple):
    """The previous frame, for motion vectors: the scene's vertex positions float32[V, 3] at
    that frame (``animation.positions_at``) and its camera."""

    positions: Array
    camera: Camera


# The aux key under which a pipeline hands its visibility buffer to the temporal resolve.
SHARED_VISIBILITY = "visibility"


def share_visibility(aux: dict, vis: VisBuffer, cfg) -> dict:
    """``aux`` with the frame's visibility buffer added when TAA resolves the frame
    (``cfg.taa``) and the buffer is one sample per pixel: the resolve then reads the depth,
    ids and barycentrics the pipeline rasterized instead of rasterizing the frame again. TAA
    takes the entry out, so no program returns it."""
    if not getattr(cfg, "taa", False) or vis.tri_id.ndim != 2:
        return aux
    return dict(aux, **{SHARED_VISIBILITY: vis})


def visibility(scene: Scene, camera: Camera, cfg, sample_offsets=None, *,
               previous: Previous | None = None) -> VisBuffer:
    """The nearest surviving surface at each pixel (or sample): a VisBuffer of shape (H, W), or
    (S, H, W) for S > 1 ``sample_offsets``; with ``previous``, with its motion vectors and
    previous depth (``raster.motion``), else without (none computed).

    Without the alpha-test effect this is the rasterizer's own visibility. With it, every
    fragment is listed; fragments of alpha-tested materials that could be visible (not behind
    the nearest opaque fragment) are alpha-tested at their sample point through the chunked
    dispatch; the nearest survivor (lowest triangle id on ties) wins, as the rasterizer's depth
    key orders them. Counts add ``alpha_invocations`` and ``overflow`` (fragments past
    ``cfg.capacity``).
    """
    vis = _nearest(scene, camera, cfg, sample_offsets)
    if previous is None:
        return vis
    with jax.named_scope("motion_vectors"):
        motion, prev_depth = motion_vectors(vis.tri_id, vis.bary, scene.faces, scene.positions,
                                            camera, previous.positions, previous.camera,
                                            cfg.width, cfg.height)
    return dataclasses.replace(vis, motion=motion, prev_depth=prev_depth)


def _nearest(scene: Scene, camera: Camera, cfg, sample_offsets) -> VisBuffer:
    offsets = sample_patterns.validate(sample_offsets or sample_patterns.CENTER)
    cull = bool(getattr(cfg, "cull_backfaces", False))
    faces = opaque_faces(scene)  # transparent surfaces are the transparent pass's
    if not scene.effects.alpha_test:
        vis = raster_visbuffer(clip_vertices(scene, camera, cfg), faces, cfg,
                               cull_backfaces=cull, sample_offsets=offsets)
        return VisBuffer(vis.tri_id, vis.depth, vis.bary, vis.dbary_dx, vis.dbary_dy,
                         dict(vis.counts, alpha_invocations=jnp.int32(0), overflow=jnp.int32(0)))
    clip = clip_vertices(scene, camera, cfg)
    per = [_alpha_visibility(scene, camera, clip, faces, cfg, off, cull) for off in offsets]
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


def is_transparent(scene: Scene, tri: Array) -> Array:
    """bool[N]: the triangle's material blends (always False without the transparency effect)."""
    if not scene.effects.transparency:
        return jnp.zeros(tri.shape, bool)
    return (scene.materials.blend[scene.tri_material[jnp.maximum(tri, 0)]] != 0) & (tri >= 0)


def faces_where(scene: Scene, keep: Array) -> Array:
    """The scene's faces with the triangles not kept made degenerate (all three corners vertex
    0): they cover no pixel, and every triangle keeps its index, so ids stay the scene's."""
    return jnp.where(keep[:, None], scene.faces, 0)


def opaque_faces(scene: Scene) -> Array:
    """The faces the opaque passes rasterize: all of them without transparency, else all but
    the blended ones."""
    if not scene.effects.transparency:
        return scene.faces
    return faces_where(scene, ~is_transparent(scene, jnp.arange(scene.num_triangles)))


def _alpha_visibility(scene, camera, clip, faces, cfg, offset, cull) -> VisBuffer:
    w, h, cap = cfg.width, cfg.height, cfg.capacity
    n_pix = w * h
    fr = raster_fragments(clip, faces, cfg, cull_backfaces=cull, sample_offset=offset)
    pix = jnp.where(fr.valid, fr.pixel, n_pix)
    tested = is_alpha_tested(scene, fr.tri) & fr.valid
    inf = float("inf")
    z_opaque = jnp.full((n_pix,), inf).at[pix].min(
        jnp.where(fr.valid & ~tested, fr.depth, inf), mode="drop")
    candidate = tested & (fr.depth <= z_opaque.at[pix].get(mode="fill", fill_value=0.0))
    with jax.named_scope("alpha_test"):
        keep_f, tested_work = dispatch.shade(
            dispatch.WorkList.of(candidate),
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
    counts = {"fragments": fr.count, "alpha_invocations": tested_work.invocations,
              "overflow": fr.overflowed.astype(jnp.int32)}
    return VisBuffer(tri, depth, bary, ddx, ddy, counts)
