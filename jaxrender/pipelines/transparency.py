"""The transparent pass: blended surfaces composited over a pipeline's opaque result.

Deferred, visibility-buffer, checkerboard, DACS and TADS shading hold one surface per pixel,
so, as engines do, they resolve the opaque surfaces first and then run a forward pass over the
transparent ones (``transparent_pass``); forward draws its opaque triangles, then the same
pass over the transparent ones (``blend_fragments``); the reference does both per sub-sample.

Plan: the transparent triangles' fragment list (the opaque triangles made degenerate, so ids
stay the scene's), every fragment strictly in front of the opaque depth of its pixel. Shade:
those fragments through the shared ``shade()`` plus the material's ``opacity``
(``layer_shader``): with the auto chunk, every entry of the list's filled prefix in one launch
with the test and the composite, those not in front as idle lanes (``blend_on_prefix``);
with a chunk given or a ``JAXRENDER_DISPATCH`` mode named, compacted into one work list and
dispatched in chunks. Reconstruct, by ``oit``:

- "sorted": the exact per-pixel sort of the fragment list, back to front (or, for forward's
  ``sort_transparent = false``, in submission order), blended into a k-buffer of static depth
  ``transparent_layers`` per pixel: a pass blends each pixel's next ``transparent_layers``
  layers, back to front, over the image so far (over: c = a s + (1 - a) c; additive:
  c = c + a s). A pixel with more layers runs further passes (``transparent_overflow =
  "chunks"``, the same image as a deeper buffer) or the frame is refused naming the cap
  ("error"); a layer is never dropped.
- "weighted": weighted blended OIT (McGuire and Bavoil 2013, eq. 7 weights): no sort;
  c = sum(w a s) / sum(w a) (1 - prod(1 - a)) + prod(1 - a) c0, w = a max(1e-2, min(3e3,
  10 / (1e-5 + (z/5)^2 + (z/200)^6))), z the view depth; additive layers are added
  unattenuated (the order-independent approximation of their attenuation).

Counts from the work: ``transparent_invocations`` (fragments shaded), ``transparent_layers_mean``
(over the pixels with a layer) and ``_max``, ``transparent_passes``, ``transparent_bytes``
(each layer's k-buffer entry written and read). A scene without the transparency effect
compiles none of this.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.compaction import compact_indices
from jaxrender.fusion import materialize, whole_rows
from jaxrender.pipelines.base import BLENDING_DEFAULTS
from jaxrender.pipelines.quads import segment_starts
from jaxrender.pipelines.visibility import (clip_vertices, faces_where, is_transparent, points_at,
                                            raster_fragments)
from jaxrender.scene.effects import BLEND_ADDITIVE, BLEND_OVER
from jaxrender.shading import opacity, shade, texture_sample, view_depth
from jaxrender.sorting import lex_sort, on_prefix, prefix_sizes
from jaxrender.types import Array

LAYER_BYTES = 20  # a k-buffer entry: premultiplied RGB and transmittance (4 float32), a depth
ONE_BITS = 0x3F800000  # float32 1.0: window depths in [0, 1] order as these integer bits
LAYER_CHANNELS = 5  # rgb radiance, opacity, view depth
ORDERS = ("depth", "submission")


class BlendSettings(NamedTuple):
    """oit ("sorted" | "weighted"), layers (k-buffer depth), overflow ("chunks" | "error"),
    order ("depth": back to front; "submission": draw order, forward unsorted)."""

    oit: str = "sorted"
    layers: int = 8
    overflow: str = "chunks"
    order: str = "depth"


def settings_of(cfg) -> BlendSettings:
    order = "depth" if getattr(cfg, "sort_transparent", True) else "submission"
    return BlendSettings(getattr(cfg, "oit", "sorted"), int(getattr(cfg, "transparent_layers", 8)),
                         getattr(cfg, "transparent_overflow", "chunks"), order)


def check_settings(scene, cfg) -> None:
    """Nothing accepted and ignored: blending settings need a scene that blends."""
    if scene.effects.transparency:
        return
    for key, default in dict(BLENDING_DEFAULTS, sort_transparent=True).items():
        if getattr(cfg, key, default) != default:
            raise ValueError(f"{key} has no effect: scene {scene.name!r} has no transparent "
                             f"material (effects.transparency is off)")


def refuse_transparency(scene, pipeline: str) -> None:
    """For a pipeline (or a setting) that cannot blend: refuse a scene that does, loudly."""
    if scene.effects.transparency:
        raise ValueError(f"{pipeline} does not render transparent surfaces yet; scene "
                         f"{scene.name!r} has blended materials (effects.transparency)")


def layer_shader(scene, camera):
    """points -> float32[N, 5]: the shared ``shade()`` radiance, the opacity, the view depth."""
    def fn(points):
        # The texture looked up once and stored: the radiance and the opacity both read it,
        # and XLA filtered it again in each of their fusions.
        texel = materialize(texture_sample(points, scene)) if scene.effects.textures else None
        # Stored apart before they are joined: a fusion that writes all five channels runs
        # a thread per channel, each evaluating the lights; ``shade``'s three share one.
        rgb, a, z = whole_rows((shade(points, scene, texel=texel),
                                opacity(points, scene, texel=texel), view_depth(points, camera)))
        return jnp.concatenate([rgb, a[:, None], z[:, None]], axis=-1)

    return fn


class Layers(NamedTuple):
    """Transparent fragments of one sample: pixel, tri, depth int32/float32[F]; front bool[F]
    (in front of the opaque depth: the ones shaded and blended); values float32[F, 5]
    (``layer_shader``'s, valid where front); live int32[] or None: no entry at or past it is
    front (a fragment list's filled prefix), so the composite sorts only that prefix."""

    pixel: Array
    tri: Array
    depth: Array
    front: Array
    values: Array
    live: Array | None = None


def in_front(valid: Array, pixel: Array, depth: Array, opaque_depth: Array,
             n_pix: int) -> Array:
    """bool[F]: a fragment list's entries (its columns ``valid``, ``pixel``, ``depth``)
    strictly in front of the opaque depth float32[P] (GL_LESS against the opaque pass's depth
    buffer, no depth write)."""
    z = opaque_depth.at[jnp.where(valid, pixel, n_pix)].get(mode="fill", fill_value=0.0)
    return valid & (depth < z)


def transparent_fragments(scene, clip, cfg, sample_offset=(0.5, 0.5)):
    """The fragment list of the transparent triangles alone (``raster_fragments``)."""
    faces = faces_where(scene, is_transparent(scene, jnp.arange(scene.num_triangles)))
    return raster_fragments(clip, faces, cfg, cull_backfaces=bool(cfg.cull_backfaces),
                            sample_offset=sample_offset)


def front_work(fr, opaque_depth: Array, n_pix: int) -> tuple[Array, dispatch.WorkList]:
    """(``in_front``, those fragments as one compacted work list), both read off the fragment
    list's filled prefix only (``on_prefix``)."""
    def on_filled(part, depth):
        front = in_front(*part, depth, n_pix)
        items, count = compact_indices(front, front.shape[0])
        return (front, items), count

    (front, items), count = on_prefix(on_filled, live_fragments(fr),
                                      (fr.valid, fr.pixel, fr.depth), opaque_depth,
                                      fill=(False, 0))
    return front, dispatch.WorkList(items, count)


def live_fragments(fr) -> Array:
    """int32: the entries of a fragment list that hold a fragment (all in its first ones)."""
    return jnp.minimum(fr.count, fr.pixel.shape[0])


def shade_layers(scene, camera, fr, front, work, points_of, chunk: int):
    """Shade the ``front`` fragments listed in ``work`` (``front_work``). Returns (Layers,
    WorkList)."""
    values, work = layer_values(scene, camera, front, work, points_of, chunk)
    return Layers(fr.pixel, fr.tri, fr.depth, front, values, live_fragments(fr)), work


def layer_values(scene, camera, front: Array, work, points_of, chunk: int):
    """``layer_shader``'s values float32[F, 5] of the fragments listed in ``work``, dispatched
    in chunks (zero elsewhere). Returns (values, WorkList)."""
    values = jnp.zeros((front.shape[0], LAYER_CHANNELS), jnp.float32)
    return dispatch.shade(work, points_of, layer_shader(scene, camera), values, chunk)


def transparent_pass(scene, camera, image: Array, opaque_depth: Array, cfg):
    """The forward transparent pass after an opaque resolve: image float32[H, W, 3] and its
    depth float32[H, W] (1 where empty) -> (image, counts to merge with ``merge_counts``).
    Returns the image unchanged and no counts for a scene without transparency."""
    check_settings(scene, cfg)
    if not scene.effects.transparency:
        return image, {}
    with jax.named_scope("transparent"):
        clip = clip_vertices(scene, camera, cfg)
        with jax.named_scope("fragments"):
            fr = transparent_fragments(scene, clip, cfg)
        return blend_fragments(scene, camera, clip, fr, image, opaque_depth.reshape(-1), cfg)


def blend_fragments(scene, camera, clip, fr, image: Array, opaque_depth: Array, cfg):
    """The transparent fragment list ``fr``'s layers in front of opaque_depth float32[P]
    shaded and blended over image float32[H, W, 3]. Returns (image, counts)."""
    h, w = image.shape[:2]
    if dispatch.launches_once(cfg.chunk):
        # Its lanes are left out of the counts: they follow the list's capacity, which like
        # ``chunk`` must leave a frame's counts as they are (OUTPUT_NEUTRAL).
        out, counts, _ = blend_on_prefix(scene, camera, clip, fr, image.reshape(-1, 3),
                                         opaque_depth, cfg)
        return out.reshape(h, w, 3), counts
    with jax.named_scope("front"):
        front, work = front_work(fr, opaque_depth, w * h)

    def points_of(items):
        return points_at(scene, camera, clip, cfg, fr.tri[items], fr.pixel[items])

    with jax.named_scope("layer_shading"):
        layers, work = shade_layers(scene, camera, fr, front, work, points_of, cfg.chunk)
    with jax.named_scope("composite"):
        out, counts = composite(scene, layers, image.reshape(-1, 3), settings_of(cfg))
    counts["transparent_invocations"] = work.invocations
    counts["overflow"] = counts["overflow"] + fr.overflowed.astype(jnp.int32)
    return out.reshape(h, w, 3), counts


def blend_on_prefix(scene, camera, clip, fr, background: Array, opaque_depth: Array, cfg):
    """``transparent_pass``'s depth test, shading and composite in one launch over the fragment
    list's filled prefix (``on_prefix``: one host read), where the chunked dispatch reads the
    host once a launch and scatters into an array the size of the whole list. Past the shortest
    prefix every entry runs the layer shader, those not in front as idle lanes: the prefix
    lengths step by at most 1.5x, so at most a third of the lanes idle past the live fragments.
    A list that fits the shortest prefix (an eighth of its capacity, half a screen by default)
    has its front fragments compacted and shaded in chunks instead, so that a few fragments do
    not launch half a screen of lanes. Each prefix length compiles its own copy of the layer
    shader, and the longest shades the whole capacity at once (its temporaries included).
    Returns (image float32[P, 3], counts, the layer shader's lanes launched int32)."""
    n_pix, shader, settings = background.shape[0], layer_shader(scene, camera), settings_of(cfg)
    shortest = prefix_sizes(fr.pixel.shape[0])[0]

    def on_filled(part, bg):
        valid, pixel, tri, depth = part
        front = in_front(valid, pixel, depth, opaque_depth, n_pix)

        def points_of(items):
            return points_at(scene, camera, clip, cfg, tri[items], pixel[items])

        with jax.named_scope("layer_shading"):
            if pixel.shape[0] == shortest:
                values, work = layer_values(scene, camera, front, dispatch.WorkList.of(front),
                                            points_of, 0)
                lanes = work.lanes
            else:
                points = points_of(jnp.arange(pixel.shape[0], dtype=jnp.int32))
                # Stored whole: the composite's sort gathers the values in another order.
                values = whole_rows(shader(dataclasses.replace(points,
                                                               valid=points.valid & front)))
                lanes = jnp.int32(pixel.shape[0])
        with jax.named_scope("composite"):
            image, counts = composite_list(scene, Layers(pixel, tri, depth, front, values), bg,
                                           settings)
        return (), (image, counts, lanes)

    _, (image, counts, lanes) = on_prefix(on_filled, live_fragments(fr),
                                          (fr.valid, fr.pixel, fr.tri, fr.depth), background)
    counts["transparent_invocations"] = counts["transparent_fragments"]
    counts["overflow"] = counts["overflow"] + fr.overflowed.astype(jnp.int32)
    return image, counts, lanes


def merge_counts(counts: dict, transparent: dict, shading_counted: bool = False) -> dict:
    """A pipeline's counts with its transparent pass's: the shading and bytes added to
    ``shade_invocations`` and ``bytes_intermediate``, the overflows summed. With
    ``shading_counted`` (forward: counted with the quads of both passes), the shading is
    already in ``shade_invocations``."""
    if not transparent:
        return counts
    out = dict(counts, **{k: v for k, v in transparent.items() if k != "overflow"})
    if not shading_counted:
        out["shade_invocations"] = (counts["shade_invocations"]
                                    + transparent["transparent_invocations"])
    out["bytes_intermediate"] = counts["bytes_intermediate"] + transparent["transparent_bytes"]
    out["overflow"] = counts.get("overflow", jnp.int32(0)) + transparent["overflow"]
    return out


# ---------------------------------------------------------------- composite


def blend_factors(scene, layers: Layers) -> tuple[Array, Array, Array]:
    """(premultiplied colour a s float32[F, 3], transmittance float32[F]: 1 - a for over, 1 for
    additive, opacity float32[F])."""
    mode = scene.materials.blend[scene.tri_material[jnp.maximum(layers.tri, 0)]]
    a = jnp.clip(layers.values[:, 3], 0.0, 1.0)
    premult = layers.values[:, :3] * a[:, None]
    trans = jnp.where(mode == BLEND_OVER, 1.0 - a, 1.0)
    return premult, trans, a


def composite(scene, layers: Layers, background: Array, settings: BlendSettings):
    """Blend the front layers over background float32[P, 3]. Returns (image float32[P, 3],
    counts: transparent_layers_mean/_max, transparent_passes, transparent_bytes, overflow).
    With ``layers.live``, only the list's filled prefix is read (``on_prefix``): a fragment
    list is sized for a few times what a frame fills."""
    if layers.live is None:
        return composite_list(scene, layers, background, settings)

    def on_filled(part, bg):
        return (), composite_list(scene, part, bg, settings)

    _, out = on_prefix(on_filled, layers.live, layers._replace(live=None), background)
    return out


def composite_list(scene, layers: Layers, background: Array, settings: BlendSettings):
    """``composite`` over every entry of the list."""
    n_pix = background.shape[0]
    per_pixel = jnp.zeros((n_pix,), jnp.int32).at[
        jnp.where(layers.front, layers.pixel, n_pix)].add(1, mode="drop")
    n_front = jnp.sum(per_pixel)
    with_layer = jnp.sum(per_pixel > 0, dtype=jnp.int32)
    if settings.oit == "weighted":
        image = weighted_composite(scene, layers, background)
        passes, overflow = jnp.int32(0), jnp.int32(0)
    else:
        image, passes, overflow = sorted_composite(scene, layers, background, per_pixel, settings)
    counts = {
        "transparent_fragments": n_front,
        "transparent_layers_mean": n_front.astype(jnp.float32)
        / jnp.maximum(with_layer, 1).astype(jnp.float32),
        "transparent_layers_max": jnp.max(per_pixel),
        "transparent_passes": passes,
        "transparent_bytes": n_front * (2 * LAYER_BYTES),
        "overflow": overflow,
    }
    return image, counts


def sorted_composite(scene, layers: Layers, background, per_pixel, settings: BlendSettings):
    """Exact: each pixel's layers in order (farthest first, or first submitted first), blended
    in passes of ``settings.layers``. Returns (image, passes, overflow)."""
    n_pix, cap = background.shape[0], settings.layers
    premult, trans, _ = blend_factors(scene, layers)
    if settings.order == "depth":
        bits = jax.lax.bitcast_convert_type(jnp.clip(layers.depth, 0.0, 1.0), jnp.int32)
        order, limit = ONE_BITS - bits, ONE_BITS  # far first
    else:
        order, limit = layers.tri, scene.num_triangles - 1  # first drawn first
    # Out of range, so sorted last: every key of the entries not blended.
    keys = (jnp.where(layers.front, layers.pixel, n_pix), jnp.where(layers.front, order, limit + 1))
    (pix, _), (premult, trans) = lex_sort(keys, (n_pix - 1, limit), (premult, trans))
    n_entries = pix.shape[0]
    # Each pixel's layers lie together in the sorted list, farthest first, from its first
    # entry on: a pass reads layers k cap .. k cap + cap - 1 of every pixel from there.
    starts = segment_starts(pix) & (pix < n_pix)
    first = jnp.zeros((n_pix,), jnp.int32).at[jnp.where(starts, pix, n_pix)].set(
        jnp.arange(n_entries, dtype=jnp.int32), mode="drop")
    deepest = jnp.max(per_pixel)
    if settings.overflow == "chunks":
        passes, overflow = (deepest + cap - 1) // cap, jnp.int32(0)
    else:
        passes = jnp.minimum(deepest, 1)
        overflow = (deepest > cap).astype(jnp.int32)

    def one_pass(k, image):
        def blend(slot_i, img):  # back to front inside the pass: slot 0 is the farthest
            layer = k * cap + slot_i
            at = jnp.where(layer < per_pixel, first + layer, n_entries)  # none: 0 + 1 img
            c = premult.at[at].get(mode="fill", fill_value=0.0)
            t = trans.at[at].get(mode="fill", fill_value=1.0)
            return c + t[:, None] * img

        # Unrolled: the pass's layers become one chain of gathers and blends that XLA fuses
        # into one kernel, not a loop of ``cap`` small launches with a condition each.
        return jax.lax.fori_loop(0, cap, blend, image, unroll=True)

    with jax.named_scope("sorted_blend"):
        # The first pass runs unconditionally (over no layers it leaves the image bit for bit
        # as it was): a loop over all the passes reads its condition on the host once more
        # than it iterates, so a frame of one pass, the usual, costs one read, not two.
        image = jax.lax.fori_loop(1, passes, one_pass, one_pass(0, background))
    return image, passes.astype(jnp.int32), overflow


def wboit_weight(alpha: Array, view_z: Array) -> Array:
    """McGuire and Bavoil (2013), eq. 7: w(z, a) = a max(1e-2, min(3e3, 10 / (1e-5 + (|z|/5)^2
    + (|z|/200)^6)))."""
    z = jnp.abs(view_z)
    d = 10.0 / (1e-5 + jnp.square(z / 5.0) + (z / 200.0) ** 6)
    return alpha * jnp.clip(d, 1e-2, 3e3)


def weighted_composite(scene, layers: Layers, background) -> Array:
    """Weighted blended OIT of the front layers (see the module docstring)."""
    n_pix = background.shape[0]
    premult, _, a = blend_factors(scene, layers)
    mode = scene.materials.blend[scene.tri_material[jnp.maximum(layers.tri, 0)]]
    over = layers.front & (mode == BLEND_OVER)
    add = layers.front & (mode == BLEND_ADDITIVE)
    w = wboit_weight(a, layers.values[:, 4])
    at_over = jnp.where(over, layers.pixel, n_pix)
    accum = jnp.zeros((n_pix, 3), jnp.float32).at[at_over].add(premult * w[:, None], mode="drop")
    weight = jnp.zeros((n_pix,), jnp.float32).at[at_over].add(a * w, mode="drop")
    reveal = jnp.ones((n_pix,), jnp.float32).at[at_over].multiply(1.0 - a, mode="drop")
    glow = jnp.zeros((n_pix, 3), jnp.float32).at[jnp.where(add, layers.pixel, n_pix)].add(
        premult, mode="drop")
    mean = accum / jnp.maximum(weight, 1e-5)[:, None]
    return mean * (1.0 - reveal)[:, None] + reveal[:, None] * background + glow


__all__ = ["blend_fragments", "blend_on_prefix", "BlendSettings", "check_settings", "composite",
           "composite_list", "front_work", "in_front", "LAYER_BYTES", "layer_values",
           "layer_shader", "Layers", "live_fragments", "merge_counts",
           "refuse_transparency", "settings_of", "shade_layers",
           "sorted_composite", "transparent_fragments", "transparent_pass", "wboit_weight",
           "weighted_composite"]
