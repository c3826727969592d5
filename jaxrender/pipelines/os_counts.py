"""Object space's counts of a frame, read off its work: the shadels shaded, allocated, needed
and reused, the store's fill and bytes, the MIP bias, the taps read and the waves launched,
and Oxide's per-pixel marking view."""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.base import make_counts
from jaxrender.pipelines.dispatch import WorkList
from jaxrender.pipelines.os_budget import budget_counts
from jaxrender.pipelines.os_marking import mark_chunks, needed_shadels, taps
from jaxrender.pipelines.os_memory import memory_counts
from jaxrender.pipelines.os_sheet import LANES
from jaxrender.pipelines.waves import count_waves

SHADEL_BYTES = 12  # float32 RGB per shadel in the store


def frame_counts(scene, sheet, cfg, fp, res, work: WorkList, out, vis):
    """Object space's counts and aux views of a frame from its Residency ``res``, shading
    WorkList and Resolved final pass ``out`` (the pixels' rows only)."""
    w, h = cfg.width, cfg.height
    nc = sheet.n_chunks
    al, owned_slot, reused = res.al, res.owned_slot, res.reused
    t = al.taps
    covered = jnp.sum(fp.covered, dtype=jnp.int32)
    needed, owned, row_of = needed_shadels(sheet, al.taps, al.page, owned_slot)
    need_n = jnp.sum(needed, axis=1, dtype=jnp.int32)
    own_n = jnp.sum(owned, axis=1, dtype=jnp.int32)
    alloc_shadels = jnp.sum(owned_slot, dtype=jnp.int32)
    alloc_lanes = al.n_alloc * LANES
    shaded_chunk = (jnp.arange(owned_slot.shape[0]) < al.n_alloc) & ~reused
    chunks_shaded = jnp.sum(shaded_chunk, dtype=jnp.int32)
    inv = work.invocations
    # A shaded chunk launches all its 64 lanes (the unowned shadels idle).
    waves, util = count_waves(jnp.where(shaded_chunk, LANES, 0), cfg.wave_size, inv)
    finest = jnp.sum(mark_chunks(taps(fp, sheet, al.bias, "finest", cfg.aniso_taps), nc),
                     dtype=jnp.int32)
    taps_read = jnp.sum(t.weight > 0.0, dtype=jnp.int32)
    f32 = lambda x: jnp.asarray(x).astype(jnp.float32)  # noqa: E731
    counts = make_counts(
        shade_invocations=inv,
        helper_lanes=chunks_shaded * LANES - inv,
        covered_pixels=covered,
        waves=waves,
        lane_utilization=util,
        bytes_intermediate=(inv + jnp.sum(reused, dtype=jnp.int32) * LANES + taps_read)
        * SHADEL_BYTES,
        shadels_shaded=inv,
        shadels_allocated=alloc_shadels,
        shadels_per_pixel=f32(alloc_shadels) / jnp.maximum(f32(covered), 1.0),
        shadels_needed=jnp.sum(needed, dtype=jnp.int32),
        chunk_fill=f32(jnp.sum(needed, dtype=jnp.int32)) / jnp.maximum(f32(alloc_lanes), 1.0),
        chunks_marked=jnp.sum(al.marked, dtype=jnp.int32),
        chunks_allocated=al.n_alloc,
        chunks_shaded=chunks_shaded,
        chunks_reused=jnp.sum(reused, dtype=jnp.int32),
        store_capacity_shadels=jnp.int32(cfg.store_chunks * LANES),
        store_bytes=jnp.float32(cfg.store_chunks * LANES * SHADEL_BYTES),  # may pass 2^31
        store_bytes_used=f32(alloc_lanes) * SHADEL_BYTES,
        mip_bias=al.bias,
        mip_bias_steps=al.bias_steps,
        trilinear_overhead=f32(al.n_alloc) / jnp.maximum(f32(finest), 1.0),
        mip_chain_memory=jnp.float32(sheet.n_chunks / max(sheet.level0_chunks, 1)),
        missing_taps=out.missing,
        unowned_taps=out.unowned,
        alpha_invocations=vis.counts["alpha_invocations"],
        overflow=out.overflow,
        **memory_counts(sheet, al.page, al.slot_chunk),
        **({} if res.budget is None else budget_counts(res.budget)),
    )
    # Oxide's marking view: per pixel, the chunk its heaviest tap reads: 1 hit, 2 fully visible
    # (every owned shadel of the chunk is needed).
    k = jnp.argmax(t.weight, axis=1)
    v = jnp.take_along_axis(t.chunk, k[:, None], axis=1)[:, 0]
    full = (need_n == own_n) & (own_n > 0)
    state = jnp.where(fp.covered, jnp.where(row_of(full, v), 2, 1), 0).astype(jnp.int32)
    aux = {"chunk_state": state.reshape(h, w), "mip_level": t.lod.reshape(h, w),
           "object": jnp.where(fp.covered, fp.obj, -1).reshape(h, w)}
    return counts, aux


__all__ = ["SHADEL_BYTES", "frame_counts"]
