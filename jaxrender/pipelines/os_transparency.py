"""Object-space shading of transparent surfaces, as Oxide shades them: like any other surface.

Every transparent fragment in front of the opaque depth (``transparency.in_front``) is one more
screen sample of the object-space pipeline: its footprint joins the pixels' (``join``), so its
filter taps mark the chunks it reads and the allocation places them in the store beside the
opaque ones; the shadels of transparent triangles are shaded by the same dispatch as all the
others. In the final pass each such fragment reads the store through its taps, like a pixel,
takes its opacity from its material there (the texture's alpha at the fragment, as the pass
samples it) and the layers are composited over the opaque resolve by the shared
``transparency.composite`` (sorted, or weighted blended OIT).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.pipelines.os_marking import Footprint, footprint
from jaxrender.pipelines.os_sheet import LANES
from jaxrender.pipelines.transparency import (Layers, check_settings, composite, in_front,
                                              settings_of, transparent_fragments)
from jaxrender.pipelines.visibility import clip_vertices, is_transparent
from jaxrender.raster.resolve import pair_barycentrics
from jaxrender.shading import opacity, surface_points, view_depth
from jaxrender.types import Array


class Blended(NamedTuple):
    """The transparent fragments of a frame: the fragment list ``fr``, ``front`` bool[F] and
    their surface points' barycentrics (bary, ddx, ddy float32[F, 3]) at the pixel centre."""

    fr: object
    front: Array
    bary: Array
    ddx: Array
    ddy: Array


def transparent_samples(scene, sheet, camera, cfg, vis, fp: Footprint):
    """(the footprints of the pixels and of the transparent fragments in front, joined; the
    Blended fragments), or (fp, None) for a scene without transparency."""
    check_settings(scene, cfg)
    if not scene.effects.transparency:
        return fp, None
    w, h = cfg.width, cfg.height
    with jax.named_scope("transparent_marking"):
        clip = clip_vertices(scene, camera, cfg)
        fr = transparent_fragments(scene, clip, cfg)
        front = in_front(fr, vis.depth.reshape(-1), w * h)
        tri = jnp.where(front, fr.tri, -1)
        b, dx, dy = pair_barycentrics(clip, scene.faces, tri, fr.pixel % w, fr.pixel // w, w, h)
        fp_t = footprint(scene, sheet, tri, b, dx, dy)
    joined = Footprint(*(jnp.concatenate([a, t]) for a, t in zip(fp, fp_t)))
    return joined, Blended(fr, front, b, dx, dy)


def pixel_rows(tree, n_pix: int):
    """The first ``n_pix`` rows of every array of a pytree (the pixels' part of a joined list)."""
    return jax.tree_util.tree_map(lambda a: a[:n_pix], tree)


def blend_layers(scene, camera, blended: Blended | None, rows: Array, image: Array, cfg):
    """Composite the transparent fragments' store reads (``rows`` float32[P + F, 3]: the final
    pass's filtered reads of the joined list) over the opaque image. Returns (image, counts)."""
    if blended is None:
        return image, {}
    h, w = image.shape[:2]
    fr = blended.fr
    with jax.named_scope("transparent_resolve"):
        pts = surface_points(scene, camera, jnp.where(blended.front, fr.tri, -1), blended.bary,
                             blended.ddx, blended.ddy)
        a = jnp.where(blended.front, opacity(pts, scene), 0.0)
        z = view_depth(pts, camera)
        values = jnp.concatenate([rows[w * h:], a[:, None], z[:, None]], axis=-1)
        layers = Layers(fr.pixel, fr.tri, fr.depth, blended.front, values,
                        jnp.minimum(fr.count, fr.pixel.shape[0]))
        out, counts = composite(scene, layers, image.reshape(-1, 3), settings_of(cfg))
    counts["overflow"] = counts["overflow"] + fr.overflowed.astype(jnp.int32)
    return out.reshape(h, w, 3), counts


def transparent_shadels(scene, sheet, slot_chunk: Array, work) -> Array:
    """int32: the shaded shadels (of the dispatch's work list) owned by transparent triangles."""
    items = work.items  # slot * LANES + lane
    chunk = slot_chunk[jnp.minimum(items // LANES, slot_chunk.shape[0] - 1)]
    owner = sheet.owner[jnp.maximum(chunk, 0) * LANES + items % LANES]
    live = jnp.arange(items.shape[0]) < work.count
    return jnp.sum(live & (owner >= 0) & is_transparent(scene, owner), dtype=jnp.int32)


def merge_os_counts(counts: dict, extra: dict, shaded_transparent: Array) -> dict:
    """object_space's counts with the transparent layers' (their shading is in the store's)."""
    if not extra:
        return counts
    out = dict(counts, **{k: v for k, v in extra.items() if k != "overflow"})
    out["transparent_shadels_shaded"] = shaded_transparent
    out["transparent_invocations"] = shaded_transparent
    out["overflow"] = counts["overflow"] + extra["overflow"]
    return out
