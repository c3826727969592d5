"""Temporal anti-aliasing: one temporal resolve that any pipeline adds after its own (``taa =
true``), as the engines ship it.

Each frame the projection is jittered by a Halton(2, 3) offset (``taa_phases`` phases, in
(-0.5, 0.5) pixels); the pipeline renders its frame with that camera; then the resolve:

- visibility: the frame's depth, object ids and motion vectors (``raster.motion``, exact from
  the previous frame's vertex positions and camera); pixels that show nothing move as the far
  plane under the camera (``scene.reprojection``);
- history: the previous output sampled at the reprojected position (bilinear or Catmull-Rom,
  ``taa_history``), rejected where the surface was disoccluded (``raster.motion.disoccluded``:
  off screen, or the previous pixels around the point do not hold its object at its depth);
- bound: the history clamped to the current 3x3 neighbourhood's box in YCoCg, or clipped
  towards its mean into mean +- sigma (variance clipping), ``taa_clip``;
- blend: ``taa_alpha * current + (1 - taa_alpha) * history`` where history is kept, the
  current frame elsewhere.

State: ``History`` (output, depth, object ids, unjittered camera of the previous frame). The
resolve reads the visibility buffer the pipeline rasterized (deferred, the visibility buffer,
checkerboard, DACS, object space hand theirs over) and adds its motion vectors; a pipeline with
none of one sample per pixel (forward, MSAA deferred, the reference) gets its own pass. Counts: ``taa_history_reads`` (pixels whose history was read)
and ``taa_rejections`` (of those, rejected as disoccluded), read off the masks that drive the
blend.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.visibility import SHARED_VISIBILITY, Previous, visibility
from jaxrender.raster.motion import disoccluded, motion_vectors, previous_position
from jaxrender.scene.animation import positions_at
from jaxrender.scene.camera import Camera, with_jitter_px, without_jitter
from jaxrender.scene.camera_path import halton
from jaxrender.scene.reprojection import reproject_pixels
from jaxrender.types import Array, Frame

DISOCCLUSION_TOLERANCE = 0.01  # relative linear depth, beyond the 3x3 neighbourhood's range
VARIANCE_GAMMA = 1.0  # the box of variance clipping: mean +- gamma * sigma


class History(NamedTuple):
    image: Array  # float32[H, W, 3] the previous output
    depth: Array  # float32[H, W]
    objects: Array  # int32[H, W], -1 where empty
    camera: Camera  # unjittered
    valid: Array  # bool[]: there is a previous frame


def init(scene, camera: Camera, cfg) -> History:
    h, w = cfg.height, cfg.width
    return History(jnp.zeros((h, w, 3), jnp.float32), jnp.ones((h, w), jnp.float32),
                   jnp.full((h, w), -1, jnp.int32), without_jitter(camera), jnp.asarray(False))


def jitter_offsets(phases: int) -> np.ndarray:
    """float32[phases, 2] Halton(2, 3) offsets in (-0.5, 0.5) pixels (x right, y down)."""
    return (np.stack([halton(phases, 2), halton(phases, 3)], 1) - 0.5).astype(np.float32)


def jittered(camera: Camera, t: Array, cfg) -> Camera:
    with jax.named_scope("taa_jitter"):
        offs = jnp.asarray(jitter_offsets(int(cfg.taa_phases)))
        return with_jitter_px(camera, offs[t % int(cfg.taa_phases)], cfg.width, cfg.height)


# ---------------------------------------------------------------- colour and filters


def to_ycocg(c: Array) -> Array:
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    return jnp.stack([0.25 * r + 0.5 * g + 0.25 * b, 0.5 * r - 0.5 * b,
                      -0.25 * r + 0.5 * g - 0.25 * b], axis=-1)


def from_ycocg(c: Array) -> Array:
    y, co, cg = c[..., 0], c[..., 1], c[..., 2]
    return jnp.stack([y + co - cg, y + cg, y - co - cg], axis=-1)


def _taps(frac: Array, kind: str) -> list[tuple[int, Array]]:
    """(integer offset from floor, weight) per tap along one axis at fraction ``frac``."""
    if kind == "bilinear":
        return [(0, 1.0 - frac), (1, frac)]
    f2, f3 = frac * frac, frac * frac * frac  # Catmull-Rom, tension 0.5
    return [(-1, -0.5 * f3 + f2 - 0.5 * frac), (0, 1.5 * f3 - 2.5 * f2 + 1.0),
            (1, -1.5 * f3 + 2.0 * f2 + 0.5 * frac), (2, 0.5 * f3 - 0.5 * f2)]


def sample_history(image: Array, position: Array, kind: str) -> Array:
    """(H, W, 3) sampled at window positions (H, W, 2), clamp to edge."""
    h, w = image.shape[:2]
    u, v = position[..., 0] - 0.5, position[..., 1] - 0.5
    x0, y0 = jnp.floor(u), jnp.floor(v)
    fx, fy = u - x0, v - y0
    x0, y0 = x0.astype(jnp.int32), y0.astype(jnp.int32)
    out = jnp.zeros(image.shape, jnp.float32)
    for dy, wy in _taps(fy, kind):
        yy = jnp.clip(y0 + dy, 0, h - 1)
        for dx, wx in _taps(fx, kind):
            xx = jnp.clip(x0 + dx, 0, w - 1)
            out = out + (wx * wy)[..., None] * image[yy, xx]
    return out


def _neighbourhood(ycocg: Array):
    """Per pixel, over its 3x3 neighbourhood (clamped at the border): min, max, mean, sigma.
    Running reductions over the nine shifted views, so no (9, H, W, 3) stack is built."""
    h, w = ycocg.shape[:2]
    pad = jnp.pad(ycocg, ((1, 1), (1, 1), (0, 0)), mode="edge")
    taps = [pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    lo, hi, total, squares = taps[0], taps[0], taps[0], taps[0] * taps[0]
    for tap in taps[1:]:
        lo, hi = jnp.minimum(lo, tap), jnp.maximum(hi, tap)
        total, squares = total + tap, squares + tap * tap
    mean = total / 9.0
    sigma = jnp.sqrt(jnp.maximum(squares / 9.0 - mean * mean, 0.0))
    return lo, hi, mean, sigma


def bound_history(history: Array, current: Array, mode: str) -> Array:
    """The history (linear RGB) bounded by the current frame's neighbourhood in YCoCg."""
    hist = to_ycocg(history)
    lo, hi, mean, sigma = _neighbourhood(to_ycocg(current))
    if mode == "clamp":
        return from_ycocg(jnp.clip(hist, lo, hi))
    # Variance clipping: move the history towards the mean until it is inside the box.
    extent = VARIANCE_GAMMA * sigma + 1e-6
    d = hist - mean
    scale = jnp.max(jnp.abs(d) / extent, axis=-1, keepdims=True)
    return from_ycocg(jnp.where(scale > 1.0, mean + d / jnp.maximum(scale, 1.0), hist))


# ---------------------------------------------------------------- the resolve


class Resolve(NamedTuple):
    image: Array
    read: Array  # bool[H, W] history sampled
    rejected: Array  # bool[H, W] history present but disoccluded


def resolve(current: Array, vis, objects: Array, hist: History, camera: Camera, cfg) -> Resolve:
    """Blend ``current`` (the pipeline's jittered frame) with the reprojected history."""
    h, w = cfg.height, cfg.width
    covered = vis.tri_id >= 0
    with jax.named_scope("taa_reproject"):
        far = reproject_pixels(jnp.ones((h, w), jnp.float32), without_jitter(camera),
                               hist.camera, None, w, h, jnp.float32(0.0))
        position = jnp.where(covered[..., None], previous_position(vis.motion), far.position)
        prev_depth = jnp.where(covered, vis.prev_depth, 1.0)
        lost = disoccluded(position, prev_depth, objects, hist.depth, hist.objects, hist.camera,
                           DISOCCLUSION_TOLERANCE)
    with jax.named_scope("taa_history"):
        sampled = sample_history(hist.image, position, cfg.taa_history)
        bounded = bound_history(sampled, current, cfg.taa_clip)
    keep = hist.valid & ~lost
    a = jnp.float32(cfg.taa_alpha)
    image = jnp.where(keep[..., None], a * current + (1.0 - a) * bounded, current)
    read = jnp.broadcast_to(hist.valid, (h, w))
    return Resolve(image, read, read & lost)


class VisSettings(NamedTuple):
    """The visibility settings of the resolve: the pipeline's own where it has them (a
    reference has no fragment capacity or culling)."""

    width: int
    height: int
    capacity: int
    chunk: int
    cull_backfaces: bool


def vis_config(cfg) -> VisSettings:
    w, h = cfg.width, cfg.height
    return VisSettings(w, h, int(getattr(cfg, "capacity", 4 * w * h)),
                       int(getattr(cfg, "chunk", 0)), bool(getattr(cfg, "cull_backfaces", False)))


def frame_visibility(scene, frame: Frame, camera: Camera, previous: Previous, cfg):
    """The jittered frame's visibility with motion vectors against ``previous``, and the frame's
    aux without the shared buffer. A pipeline that rasterized one sample per pixel handed its
    buffer over (``visibility.share_visibility``): its motion vectors are computed from its
    own ids and barycentrics. The others (forward, the reference) get a visibility pass here,
    whose fragment overflow is added to theirs."""
    aux = {k: v for k, v in frame.aux.items() if k != SHARED_VISIBILITY}
    shared = frame.aux.get(SHARED_VISIBILITY)
    if shared is None:
        return visibility(scene, camera, vis_config(cfg), previous=previous), aux, True
    with jax.named_scope("motion_vectors"):
        motion, prev_depth = motion_vectors(shared.tri_id, shared.bary, scene.faces,
                                            scene.positions, camera, previous.positions,
                                            previous.camera, cfg.width, cfg.height)
    return dataclasses.replace(shared, motion=motion, prev_depth=prev_depth), aux, False


def step(pipe, scene, static, state, camera: Camera, t: Array, cfg):
    """``pipe``'s step with TAA: state is (the pipeline's state, History)."""
    inner, hist = state
    jcam = jittered(camera, t, cfg)
    frame, inner = pipe.step(scene, static, inner, jcam, t, cfg)
    with jax.named_scope("taa"):
        previous = Previous(positions_at(scene, t - 1), hist.camera)
        vis, aux, own_pass = frame_visibility(scene, frame, jcam, previous, cfg)
        objects = jnp.where(vis.tri_id >= 0, scene.tri_object[jnp.maximum(vis.tri_id, 0)], -1)
        res = resolve(frame.image, vis, objects, hist, camera, cfg)
    counts = dict(frame.counts, taa_history_reads=jnp.sum(res.read, dtype=jnp.int32),
                  taa_rejections=jnp.sum(res.rejected, dtype=jnp.int32))
    if own_pass and "overflow" in counts:
        counts["overflow"] = counts["overflow"] + vis.counts["overflow"]
    aux = dict(aux, taa_rejected=res.rejected)
    new = History(res.image, vis.depth, objects, without_jitter(camera), jnp.asarray(True))
    return Frame(res.image, counts, aux), (inner, new)


__all__ = ["History", "bound_history", "from_ycocg", "init", "jitter_offsets", "jittered",
           "resolve", "sample_history", "step", "to_ycocg"]
