"""The reference's transparent pass: every layer of S sub-samples at once, exactly sorted,
through ``transparency``'s plan, shade and composite."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.transparency import BlendSettings, composite, front_work, shade_layers
from jaxrender.pipelines.visibility import faces_where, is_transparent
from jaxrender.raster.fragments import collect_fragments
from jaxrender.raster.rasterize import default_clip_capacity, default_work_capacity
from jaxrender.raster.resolve import pair_barycentrics
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.shading import surface_points
from jaxrender.types import Array


def sample_pass(scene, camera, clip, offsets: Array, live: Array, opaque_depth: Array,
                rgb: Array, deriv_scale: Array, cfg):
    """The exact transparent pass at S sub-samples at once: ``offsets`` int32[S, 2] fixed point
    (traced), ``live`` bool[S] (a dead sample lists nothing), the samples' opaque depths
    float32[S * P] and colours float32[S * P, 3], sample-major; texture footprints scaled by
    ``deriv_scale`` (1/k). The samples share one fragment list, one shading dispatch and one
    sort, as S * P pixels of their own; every layer sorted, any number of layers (passes of
    DEFAULT_LAYERS, counted once for the S samples). Returns (rgb, counts, with the shading
    dispatch's ``transparent_lanes`` and ``transparent_chunks``)."""
    w, h = cfg.width, cfg.height
    n_pix, n_s = w * h, offsets.shape[0]
    n_tris = scene.num_triangles
    faces = faces_where(scene, is_transparent(scene, jnp.arange(n_tris)))
    fr = collect_fragments(clip, faces, w, h, n_s * 4 * n_pix, False, offsets,
                           default_work_capacity(n_tris, w, h), default_clip_capacity(n_tris),
                           live=live)
    front, work = front_work(fr, opaque_depth, n_s * n_pix)
    off_px = offsets.astype(jnp.float32) / (1 << SUBPIXEL_BITS)

    def points_of(items):
        t, p = fr.tri[items], fr.pixel[items]
        sample, q = p // n_pix, p % n_pix
        b, dx, dy = pair_barycentrics(clip, scene.faces, t, q % w, q // w, w, h,
                                      (off_px[sample, 0], off_px[sample, 1]))
        return surface_points(scene, camera, t, b, dx * deriv_scale, dy * deriv_scale)

    layers, work = shade_layers(scene, camera, fr, front, work, points_of,
                                cfg.chunk or n_s * n_pix)
    out, counts = composite(scene, layers, rgb, BlendSettings())
    counts["transparent_invocations"] = work.invocations
    counts["transparent_lanes"], counts["transparent_chunks"] = work.lanes, work.chunks
    counts["overflow"] = counts["overflow"] + fr.overflowed.astype(jnp.int32)
    return out, counts


__all__ = ["sample_pass"]
