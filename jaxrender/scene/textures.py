"""Textures as one packed MIP atlas, so a per-point texture id and a per-point (traced) level
are a single gather (jit-friendly, one array whatever the number of textures).

Every texture is resampled to a common power-of-two square resolution R. Level l (size
s = R >> l) of texture k lives in ``atlas[k, 2R - 2s : 2R - s, :s]``: level 0 in rows [0, R),
level 1 in rows [R, R + R/2), ... down to the 1x1 level in row 2R - 2. Levels are built by 2x2
box filtering (the reference the tests compare against). Texels are linear RGBA float32; row 0
is the top of the image, and uv (0, 0) is the bottom-left corner (OBJ/GL convention); uv wraps
(repeat).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.types import Array, pytree_dataclass


@pytree_dataclass
class Textures:
    """atlas float32[K, 2R-1, R, 4]. K >= 1 (a white 1x1 placeholder when a scene has none)."""

    atlas: Array

    @property
    def resolution(self) -> int:
        return self.atlas.shape[2]

    @property
    def levels(self) -> int:
        return int(self.resolution).bit_length()


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def as_rgba(image, *, srgb: bool) -> np.ndarray:
    """An image array (H, W), (H, W, 1..4) uint8 or float in [0, 1] -> float64 RGBA, linear."""
    img = np.asarray(image)
    scale = 255.0 if img.dtype == np.uint8 else (65535.0 if img.dtype == np.uint16 else 1.0)
    img = img.astype(np.float64) / scale
    if img.ndim == 2:
        img = img[..., None]
    if img.shape[-1] == 1:
        img = np.repeat(img, 3, axis=-1)
    elif img.shape[-1] == 2:  # luminance + alpha
        img = np.concatenate([np.repeat(img[..., :1], 3, axis=-1), img[..., 1:]], axis=-1)
    rgb, a = img[..., :3], (img[..., 3:4] if img.shape[-1] == 4 else np.ones(img.shape[:2] + (1,)))
    if srgb:
        rgb = srgb_to_linear(rgb)
    return np.concatenate([rgb, a], axis=-1)


def resample(img: np.ndarray, size: int) -> np.ndarray:
    """Box/bilinear resample of an (H, W, C) image to (size, size, C) with wrap-around."""
    h, w = img.shape[:2]
    if (h, w) == (size, size):
        return img
    if h % size == 0 and w % size == 0:  # integer downscale: exact box filter
        return img.reshape(size, h // size, size, w // size, -1).mean(axis=(1, 3))
    ys = (np.arange(size) + 0.5) * h / size - 0.5
    xs = (np.arange(size) + 0.5) * w / size - 0.5
    y0, x0 = np.floor(ys).astype(int), np.floor(xs).astype(int)
    fy, fx = (ys - y0)[:, None, None], (xs - x0)[None, :, None]
    g = lambda yy, xx: img[np.mod(yy, h)][:, np.mod(xx, w)]  # noqa: E731
    return ((1 - fy) * ((1 - fx) * g(y0, x0) + fx * g(y0, x0 + 1))
            + fy * ((1 - fx) * g(y0 + 1, x0) + fx * g(y0 + 1, x0 + 1)))


def mip_chain(level0: np.ndarray) -> list[np.ndarray]:
    """2x2 box-filtered MIP chain of a square power-of-two (R, R, C) image, down to 1x1."""
    chain = [level0]
    while chain[-1].shape[0] > 1:
        a = chain[-1]
        s = a.shape[0] // 2
        chain.append(a.reshape(s, 2, s, 2, -1).mean(axis=(1, 3)))
    return chain


def pack_textures(images: list[np.ndarray], *, resolution: int | None = None,
                  max_resolution: int = 1024) -> Textures:
    """images: RGBA float arrays (linear, see ``as_rgba``). R = ``resolution`` or the largest
    side rounded up to a power of two, capped at ``max_resolution``."""
    if not images:
        return Textures(atlas=jnp.ones((1, 1, 1, 4), jnp.float32))
    if resolution is None:
        side = max(max(im.shape[:2]) for im in images)
        resolution = min(1 << int(np.ceil(np.log2(max(side, 1)))), max_resolution)
    r = int(resolution)
    if r < 1 or r & (r - 1):
        raise ValueError(f"texture resolution must be a power of two, got {r}")
    atlas = np.zeros((len(images), 2 * r - 1, r, 4), np.float32)
    for k, im in enumerate(images):
        for lvl, m in enumerate(mip_chain(resample(np.asarray(im, np.float64), r))):
            s = r >> lvl
            atlas[k, 2 * r - 2 * s: 2 * r - s, :s] = m
    return Textures(atlas=jnp.asarray(atlas))
