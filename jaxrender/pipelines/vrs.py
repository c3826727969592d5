"""Software variable-rate shading for the visibility buffer: a rate 1x1, 1x2, 2x1 or 2x2
(width x height, as D3D12_SHADING_RATE_AxB) per pixel, from a fixed setting, a per-triangle rule
(view distance, or screen-space speed of the triangle's centroid from the scene's velocity), a
rate image, or per 8x8 tile from the screen-space speed of the frame's motion vectors
(``motion``: object and camera motion alike, as Decima picks its rates).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.scene.camera import world_to_clip
from jaxrender.types import Array

RATES = ("1x1", "1x2", "2x1", "2x2")  # width x height, as D3D12_SHADING_RATE_AxB
RATE_W = (1, 1, 2, 2)
RATE_H = (1, 2, 1, 2)
VRS_MODES = ("off", "fixed", "distance", "speed", "image", "motion")
SPEED_MODES = ("distance", "speed", "motion")  # the modes vrs_thresholds apply to
RATE_TILE = 8  # pixels per side of a tile of one rate under ``motion``


def triangle_rates(scene, camera, cfg) -> Array:
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
        half_screen = jnp.asarray([cfg.width, cfg.height], jnp.float32)[None, :] * 0.5
        dd = (win(c1) - win(c0)) * half_screen
        s = jnp.sqrt(jnp.sum(dd * dd, axis=-1))
        return speed_rate(s, dd[:, 0], dd[:, 1], cfg.vrs_thresholds)
    return jnp.zeros((n,), jnp.int32)


def pixel_rates(scene, camera, cfg, vis) -> Array:
    """int32[H, W] rate code of every pixel of VisBuffer ``vis`` (0 = 1x1 where VRS is off;
    ``motion`` needs its motion vectors)."""
    h, w = cfg.height, cfg.width
    tri = vis.tri_id
    if cfg.vrs == "motion":
        return motion_rates(vis.motion, tri >= 0, cfg.vrs_thresholds)
    if cfg.vrs == "off":
        return jnp.zeros((h, w), jnp.int32)
    if cfg.vrs == "image":
        grid = np.array([[RATES.index(r) for r in row] for row in cfg.rate_image], np.int32)
        rows = np.arange(h) * grid.shape[0] // h
        cols = np.arange(w) * grid.shape[1] // w
        return jnp.asarray(grid[rows[:, None], cols[None, :]])
    return triangle_rates(scene, camera, cfg)[jnp.maximum(tri, 0)]


def speed_rate(speed: Array, dx: Array, dy: Array, thresholds) -> Array:
    """int32 rate code of a screen speed (pixels per frame) along (dx, dy): below a 1x1, from
    a to b 2x1 (1x2 for mostly vertical motion), from b 2x2."""
    a, b = thresholds
    mid = jnp.where(jnp.abs(dx) >= jnp.abs(dy), 2, 1)
    return jnp.where(speed < a, 0, jnp.where(speed < b, mid, 3)).astype(jnp.int32)


def motion_rates(motion: Array, covered: Array, thresholds) -> Array:
    """int32[H, W] rates per 8x8 tile from motion vectors float32[H, W, 2] (pixels per frame):
    a tile takes the rate of its slowest covered pixel (a tile coarsens only where all of it
    moves fast enough to blur), along the tile's mean motion; uncovered pixels 1x1."""
    h, w = covered.shape
    th, tw = -(-h // RATE_TILE), -(-w // RATE_TILE)
    pad = lambda a, fill: jnp.full((th * RATE_TILE, tw * RATE_TILE) + a.shape[2:], fill,  # noqa
                                   a.dtype).at[:h, :w].set(a)
    tiles = lambda a: a.reshape(th, RATE_TILE, tw, RATE_TILE, *a.shape[2:]).swapaxes(1, 2)  # noqa
    cov = tiles(pad(covered, False))
    mv = tiles(pad(motion, 0.0))
    speed = jnp.sqrt(jnp.sum(mv * mv, axis=-1))
    slowest = jnp.min(jnp.where(cov, speed, jnp.inf), axis=(2, 3))
    n = jnp.maximum(jnp.sum(cov, axis=(2, 3)), 1).astype(jnp.float32)
    mean = jnp.sum(jnp.where(cov[..., None], mv, 0.0), axis=(2, 3)) / n[..., None]
    rate = jnp.where(jnp.isinf(slowest), 0,
                     speed_rate(slowest, mean[..., 0], mean[..., 1], thresholds))
    per_pixel = jnp.repeat(jnp.repeat(rate, RATE_TILE, 0), RATE_TILE, 1)[:h, :w]
    return jnp.where(covered, per_pixel, 0)
