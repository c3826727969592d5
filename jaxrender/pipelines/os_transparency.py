"""Object-space shading of transparent surfaces, as Oxide shades them: like any other surface.

Every transparent fragment in front of the opaque depth (``transparency.front_work``) is one
more screen sample of the object-space pipeline: compacted into a list after the pixels, its
footprint joins theirs, so its filter taps mark the chunks it reads and the allocation places
them in the store beside the opaque ones; the shadels of transparent triangles are shaded by
the same dispatch as all the others. In the final pass each such fragment reads the store
through its taps, like a pixel, takes its opacity from its material there (the texture's alpha
at the fragment, as the pass samples it) and the layers are composited over the opaque resolve
by the shared ``transparency.composite`` (sorted, or weighted blended OIT).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxrender.pipelines.os_marking import Footprint, footprint
from jaxrender.pipelines.os_sheet import LANES
from jaxrender.pipelines.transparency import (Layers, check_settings, composite, front_work,
                                              settings_of, transparent_fragments)
from jaxrender.pipelines.visibility import clip_vertices, is_transparent
from jaxrender.raster.resolve import pair_barycentrics
from jaxrender.shading import opacity, surface_points, view_depth
from jaxrender.sorting import prefix_branch
from jaxrender.types import Array


class Blended(NamedTuple):
    """The transparent fragments in front, compacted into a list of static length C: pixel,
    tri, depth int32/int32/float32[C], front bool[C] (the first ``count`` entries), count
    int32, overflowed bool (the fragment list's), and their surface points' barycentrics (bary,
    ddx, ddy float32[C, 3]) at the pixel centre."""

    pixel: Array
    tri: Array
    depth: Array
    front: Array
    count: Array
    overflowed: Array
    bary: Array
    ddx: Array
    ddy: Array


def over_transparent_samples(scene, sheet, camera, cfg, vis, fp: Footprint, tail):
    """``tail(the samples' footprints, Blended or None)``: for a scene without transparency,
    of the pixels' footprints ``fp``; else of those joined by the transparent fragments in
    front, compacted into a list of three quarters of a screen's entries, of a screen's, or of
    the fragment list's length, the shortest that holds them (one ``lax.switch``: every
    per-sample pass after this, the marking, the allocation, the final reads, costs what the
    list holds, not the fragment capacity)."""
    check_settings(scene, cfg)
    if not scene.effects.transparency:
        return tail(fp, None)
    w, h = cfg.width, cfg.height
    with jax.named_scope("transparent_marking"):
        clip = clip_vertices(scene, camera, cfg)
        fr = transparent_fragments(scene, clip, cfg)
        _, work = front_work(fr, vis.depth.reshape(-1), w * h)
    # Every branch holds the rest of the frame (compile time): three sizes, so that layers in
    # front of over half the screen (glass) need not run a whole screen's rows.
    sizes = sorted({min(m, fr.pixel.shape[0]) for m in (3 * w * h // 4, w * h)}
                   | {fr.pixel.shape[0]})

    def with_samples(size: int):
        def branch(_):
            with jax.named_scope("transparent_marking"):
                items = work.items[:size]
                front = jnp.arange(size, dtype=jnp.int32) < work.count
                tri = jnp.where(front, fr.tri[items], -1)
                pixel = fr.pixel[items]
                b, dx, dy = pair_barycentrics(clip, scene.faces, tri, pixel % w, pixel // w, w, h)
                fp_t = footprint(scene, sheet, tri, b, dx, dy)
            joined = Footprint(*(jnp.concatenate([a, t]) for a, t in zip(fp, fp_t)))
            return tail(joined, Blended(pixel, tri, fr.depth[items], front, work.count,
                                        fr.overflowed, b, dx, dy))
        return branch

    return jax.lax.switch(prefix_branch(work.count, sizes), [with_samples(m) for m in sizes],
                          None)


def pixel_rows(tree, n_pix: int):
    """The first ``n_pix`` rows of every array of a pytree (the pixels' part of a joined list)."""
    return jax.tree_util.tree_map(lambda a: a[:n_pix], tree)


def blend_layers(scene, camera, blended: Blended | None, rows: Array, image: Array, cfg):
    """Composite the transparent fragments' store reads (``rows`` float32[P + F, 3]: the final
    pass's filtered reads of the joined list) over the opaque image. Returns (image, counts)."""
    if blended is None:
        return image, {}
    h, w = image.shape[:2]
    with jax.named_scope("transparent_resolve"):
        tri = jnp.where(blended.front, blended.tri, -1)
        pts = surface_points(scene, camera, tri, blended.bary, blended.ddx, blended.ddy)
        a = jnp.where(blended.front, opacity(pts, scene), 0.0)
        z = view_depth(pts, camera)
        values = jnp.concatenate([rows[w * h:], a[:, None], z[:, None]], axis=-1)
        layers = Layers(blended.pixel, blended.tri, blended.depth, blended.front, values,
                        blended.count)
        out, counts = composite(scene, layers, image.reshape(-1, 3), settings_of(cfg))
    counts["overflow"] = counts["overflow"] + blended.overflowed.astype(jnp.int32)
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
