"""Forward's transparent fragments: split from its draw list, tested against its final opaque
depth, shaded in its main pass, and blended here by the shared ``transparency.composite``."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.pipelines.transparency import (Layers, check_settings, composite,
                                              refuse_transparency, settings_of)
from jaxrender.pipelines.visibility import is_transparent


def forward_split(scene, draw, cfg):
    """(forward's draw list without its transparent fragments, bool[F] the transparent
    fragments), or (draw, None) for a scene without transparency."""
    check_settings(scene, cfg)
    if not scene.effects.transparency:
        return draw, None
    if draw.samples > 1 or cfg.shade_helpers:
        refuse_transparency(scene, "forward with msaa > 1 or shade_helpers")
    transparent = is_transparent(scene, draw.tri) & draw.valid
    return draw._replace(valid=draw.valid & ~transparent), transparent


def forward_front(draw, transparent, keep, cfg):
    """bool[F]: the transparent fragments in front of the final opaque depth of their pixel
    (drawn after the opaque ones, as engines order them), or None."""
    if transparent is None:
        return None
    n_pix = cfg.width * cfg.height
    z = jnp.full((n_pix,), jnp.inf).at[draw.slot].min(jnp.where(keep, draw.depth, jnp.inf),
                                                       mode="drop")
    return transparent & (draw.depth < z.at[draw.slot].get(mode="fill", fill_value=-jnp.inf))


def forward_blend(scene, draw, front, values, image, counts: dict, cfg):
    """Blend forward's shaded transparent units (``values`` from its main pass) over its opaque
    image; their shading is already in ``shade_invocations``. Returns (image, counts)."""
    if front is None:
        return image, counts
    h, w = image.shape[:2]
    live = jnp.minimum(draw.fragments, draw.pixel.shape[0])  # one sample: a sorted prefix
    layers = Layers(draw.pixel, draw.tri, draw.depth, front, values, live)
    with jax.named_scope("transparent"):
        out, extra = composite(scene, layers, image.reshape(-1, 3), settings_of(cfg))
    counts = dict(counts, **{k: v for k, v in extra.items() if k != "overflow"},
                  transparent_invocations=jnp.sum(front, dtype=jnp.int32))
    counts["bytes_intermediate"] = counts["bytes_intermediate"] + extra["transparent_bytes"]
    counts["overflow"] = counts["overflow"] + extra["overflow"]
    return out.reshape(h, w, 3), counts


__all__ = ["forward_blend", "forward_front", "forward_split"]
