"""Forward's transparent fragments: split from its draw list, tested against its final opaque
depth, and shaded and blended after its opaque units, as engines draw the transparent
geometry after the opaque (``transparency.blend_listed``, or the chunked dispatch and
``transparency.composite`` when chunks are asked for)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.pipelines.dispatch import launches_once
from jaxrender.pipelines.transparency import (Layers, blend_listed, check_settings, composite,
                                              layer_values, refuse_transparency, settings_of)
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


def forward_front(draw, transparent, z_final):
    """bool[F]: the transparent fragments in front of the final opaque depth of their slot
    (``z_final`` float32[S * P], +inf where none: drawn after the opaque ones, as engines
    order them), or None."""
    if transparent is None:
        return None
    return transparent & (draw.depth < z_final.at[draw.slot].get(mode="fill",
                                                                 fill_value=-jnp.inf))


def forward_blend(scene, camera, clip, draw, front, work, unit_points, image, counts: dict, cfg):
    """Shade forward's transparent units in front (``front`` bool[F], listed in ``work``) and
    blend them over its opaque image. With the auto chunk, only the listed units are read,
    shaded and sorted, in one launch over the list's filled prefix; with a chunk given or a
    launch mode named, they are dispatched in chunks and the composite reads the draw list's
    filled prefix. Their shading is added to ``counts``'s ``shade_invocations`` by the caller.
    Returns (image, counts)."""
    if front is None:
        return image, counts
    h, w = image.shape[:2]
    background = image.reshape(-1, 3)
    with jax.named_scope("transparent"):
        if launches_once(cfg.chunk):
            def layers_of(part):
                (items,) = part
                listed = jnp.arange(items.shape[0], dtype=jnp.int32) < work.count
                return draw.pixel[items], draw.tri[items], draw.depth[items], listed

            out, extra, _ = blend_listed(scene, camera, clip, work.count, (work.items,),
                                         layers_of, background, cfg)
        else:
            values, _ = layer_values(scene, camera, front, work, unit_points, cfg.chunk)
            live = jnp.minimum(draw.fragments, draw.pixel.shape[0])  # one sample: a prefix
            out, extra = composite(scene, Layers(draw.pixel, draw.tri, draw.depth, front,
                                                 values, live), background, settings_of(cfg))
    extra = dict(extra, transparent_invocations=work.count)
    counts = dict(counts, **{k: v for k, v in extra.items() if k != "overflow"})
    counts["bytes_intermediate"] = counts["bytes_intermediate"] + extra["transparent_bytes"]
    counts["overflow"] = counts["overflow"] + extra["overflow"]
    return out.reshape(h, w, 3), counts


__all__ = ["forward_blend", "forward_front", "forward_split"]
