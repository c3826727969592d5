"""The rasterizer's entry points: clip-space or world-space triangles -> VisBuffer.

Stages (each named for profiles): classify against the clip planes; set up and cover the
triangles that need no clipping; clip the crossing ones in chunks of ``clip_capacity`` and
cover their fans; resolve each pixel's winner to barycentrics. Every capacity here is a chunk
size, not a limit: work beyond it runs in further iterations of a loop inside the program.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache, partial

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.compaction import compact_indices
import jaxrender.raster.samples as sample_patterns
from jaxrender.raster.checks import check_mesh, check_size
from jaxrender.raster.clip import MAX_FAN, classify, clip_triangles
from jaxrender.raster.coverage import for_each_chunk
from jaxrender.raster.work_items import EMPTY_KEY, Triangles, depth_key, flat_samples
from jaxrender.raster.resolve import decode_keys, resolve
from jaxrender.raster.setup import SUBPIXEL_BITS, SetupFn, guard_band
from jaxrender.scene.camera import Camera, world_to_clip
from jaxrender.types import Array, Counts, DepthBuffer, VisBuffer


def default_work_capacity(n_tris: int, width: int, height: int) -> int:
    """Chunk size of the pixel work list: two bounding-box pixels per screen pixel plus one
    for every other triangle, rounded up to 2^16. A static chunk costs its full size whatever
    it holds, so it should fit a typical frame's items without much slack; a frame that needs
    more runs more chunks (a 1080p terrain needs about two items per pixel whatever its
    triangle count)."""
    want = 2 * width * height + n_tris // 2
    return int(min(max(1 << 16, -(-want // (1 << 16)) * (1 << 16)), 1 << 25))


# Below this many pixels "auto" keeps the bounding-box traversal on the CPU: the span
# traversal pays for itself in run time on large frames but costs compile time (over a second
# per rasterizing program on a 2-core CPU), which dominates small frames (the quickstart at
# 128x72, the tests).
SPANS_MIN_PIXELS = 1 << 16

# Elsewhere (GPU) "auto" recomputes the setup per work item when there is at least one
# triangle per this many pixels, and stores it otherwise: per item, recomputing costs more than
# gathering when many items share a triangle, and saves the setup's writes when few do (the
# crossover lies between 164k and 655k triangles at 1920x1080).
RECOMPUTE_MIN_DENSITY = 16


def default_clip_capacity(n_tris: int) -> int:
    return int(min(n_tris, 4096))


def rasterize_clip(
    clip: Array,
    faces: Array,
    width: int,
    height: int,
    *,
    cull_backfaces: bool = False,
    sample_offsets=None,
    work_capacity: int | None = None,
    clip_capacity: int | None = None,
    donate: VisBuffer | None = None,
) -> VisBuffer:
    """Rasterize triangles given by clip-space vertices float32[V, 4] and faces int32[T, 3].

    Returns a VisBuffer of shape (H, W) for one sample per pixel (the centre unless
    ``sample_offsets`` says otherwise), or (S, H, W) when ``sample_offsets`` holds S > 1 offsets
    in [0, 1)^2 (see ``jaxrender.raster.samples``). Triangles with a NaN or infinite vertex are
    dropped and counted in ``counts['dropped_nonfinite']``; other bad input raises ValueError.

    ``donate``: the previous result of the same call (same kind and size), for a frame loop
    (``vis = rasterize_clip(..., donate=vis)``). This call's output takes over its device
    memory and it is deleted. On a GPU that keeps every buffer at the same address from frame
    to frame, so XLA need not update its CUDA graphs before each launch, which is a
    noticeable part of a small frame's time.
    """
    return _rasterize_checked(clip, faces, width, height, True, cull_backfaces, sample_offsets,
                              work_capacity, clip_capacity, donate)


def rasterize_depth_clip(clip: Array, faces: Array, width: int, height: int,
                         **kwargs) -> DepthBuffer:
    """``rasterize_clip`` without barycentrics: the nearest triangle's id and depth per pixel
    (bit for bit those of the VisBuffer), for a depth pre-pass, a shadow map or an id buffer.
    Skips the resolve step (about a quarter of a 1080p frame's kernel time on a GPU) and two
    thirds of the output."""
    return _rasterize_checked(clip, faces, width, height, False, **kwargs)


def _rasterize_checked(clip, faces, width, height, barycentrics, cull_backfaces=False,
                       sample_offsets=None, work_capacity=None, clip_capacity=None, donate=None):
    # Per call only what the arrays can change; the rest is worked out once per setting, so a
    # frame loop's Python stays small beside a sub-millisecond frame.
    width, height = check_size(width, height)
    offsets = _fixed_offsets(None if sample_offsets is None else
                             tuple(tuple(float(v) for v in o) for o in sample_offsets))
    check_mesh(clip, faces, "clip", 4)
    n_tris = faces.shape[0]
    static = dict(
        width=width,
        height=height,
        cull_backfaces=bool(cull_backfaces),
        offsets=offsets,
        work_capacity=int(work_capacity or _default_work_capacity(n_tris, width, height)),
        clip_capacity=int(clip_capacity or default_clip_capacity(n_tris)),
        barycentrics=barycentrics,
    )
    args = (_as_dtype(clip, jnp.float32), _as_dtype(faces, jnp.int32))
    if _tracing(args):  # inside the caller's jit, scan, vmap...: part of its program
        if donate is not None:
            raise ValueError("rasterize: donate is for a call made on its own; inside jax.jit "
                             "XLA places the buffers itself")
        return rasterize_traced(*args, **static)
    if donate is None:
        return rasterize_program(*args, **static)
    _check_donated(donate, barycentrics, len(offsets), width, height)
    return rasterize_donating(*args, donate, **static)


_default_work_capacity = lru_cache(maxsize=64)(default_work_capacity)


@lru_cache(maxsize=64)
def _fixed_offsets(sample_offsets) -> tuple[tuple[int, int], ...]:
    return sample_patterns.to_fixed(
        sample_patterns.validate(sample_offsets or sample_patterns.CENTER), SUBPIXEL_BITS)


try:  # jax has no public test for "no trace is active"
    from jax._src.core import trace_state_clean as _no_trace_active
except ImportError:  # pragma: no cover - then only traced arguments are seen
    def _no_trace_active() -> bool:
        return True


def _tracing(args) -> bool:
    """Whether this call is being traced into a caller's program: arrays closed over by a jit
    or scan body are concrete, so the arguments alone do not tell."""
    return any(isinstance(x, jax.core.Tracer) for x in args) or not _no_trace_active()


def _as_dtype(x, dtype):
    """``jnp.asarray(x, dtype)``, without its cost (tens of us) when ``x`` already is one."""
    return x if isinstance(x, jax.Array) and x.dtype == dtype else jnp.asarray(x, dtype)


def rasterize(
    positions: Array, faces: Array, camera: Camera, width: int, height: int, **kwargs
) -> VisBuffer:
    """Rasterize world-space positions float32[V, 3] seen through ``camera`` (see rasterize_clip)."""
    return rasterize_clip(_world_clip(positions, faces, camera, width, height), faces, width,
                          height, **kwargs)


def rasterize_depth(
    positions: Array, faces: Array, camera: Camera, width: int, height: int, **kwargs
) -> DepthBuffer:
    """World-space ``rasterize_depth_clip``: ids and depth, no barycentrics."""
    return rasterize_depth_clip(_world_clip(positions, faces, camera, width, height), faces,
                                width, height, **kwargs)


def _world_clip(positions, faces, camera, width, height):
    width, height = check_size(width, height)
    check_mesh(positions, faces, "positions", 3)
    return world_to_clip(jnp.asarray(positions, jnp.float32), camera, width / height)


_STATIC = ("width", "height", "cull_backfaces", "offsets", "work_capacity", "clip_capacity",
           "traversal", "barycentrics")


def _rasterize_impl(clip, faces, *, width, height, cull_backfaces, offsets, work_capacity,
                    clip_capacity, traversal="auto", barycentrics=True):
    with jax.enable_x64(True):
        return _rasterize_x64(
            clip, faces, width, height, cull_backfaces, offsets, work_capacity, clip_capacity,
            traversal, barycentrics,
        )


# The jitted core without input checks, for use inside other programs (the pipelines) and
# in tests.
rasterize_traced = jax.jit(_rasterize_impl, static_argnames=_STATIC)

# A call on its own (the entry points with concrete arrays; the benchmarks) compiles with
# XLA GPU's graph threshold at 1: a run of fewer than 5 kernels (its default) is launched
# kernel by kernel, and the three after the coverage loop (decode, counts) then cost a launch
# each. As one CUDA graph a small donated depth call is about a fifth faster, with no change
# at larger sizes. Other backends ignore
# the option; jax accepts options on a top-level jit only, hence the separate entries.
_OPTIONS = {"xla_gpu_graph_min_graph_size": 1}
rasterize_program = jax.jit(_rasterize_impl, static_argnames=_STATIC, compiler_options=_OPTIONS)


# keep_unused: an argument the program does not read is otherwise pruned, and its buffers
# would be freed instead of becoming the outputs.
@partial(jax.jit, static_argnames=_STATIC, donate_argnames="donate", keep_unused=True,
         compiler_options=_OPTIONS)
def rasterize_donating(clip, faces, donate, **static):
    del donate  # only its buffers are wanted: XLA writes the outputs into them
    return _rasterize_impl(clip, faces, **static)


def _check_donated(donate, barycentrics: bool, n_samples: int, width: int, height: int):
    kind = VisBuffer if barycentrics else DepthBuffer
    shape = (height, width) if n_samples == 1 else (n_samples, height, width)
    if type(donate) is not kind or np.shape(donate.tri_id) != shape or not isinstance(
            donate.counts, Counts):
        got = type(donate).__name__
        if hasattr(donate, "tri_id"):
            got += f" of shape {np.shape(donate.tri_id)}"
            got += f" with counts of type {type(getattr(donate, 'counts', None)).__name__}"
        raise ValueError(f"rasterize: donate must be a {kind.__name__} of shape {shape} (the "
                         f"previous result of the same call), got {got}")
    leaves = jax.tree_util.tree_leaves(donate)
    if any(leaf.is_deleted() for leaf in leaves if isinstance(leaf, jax.Array)):
        raise ValueError("rasterize: donate was given a result whose buffers are already gone "
                         "(donated before); pass the latest frame's result")
    if len({id(leaf) for leaf in leaves}) != len(leaves):
        raise ValueError("rasterize: donate was given a result whose fields share an array; "
                         "each field needs its own buffer")


TRAVERSALS = ("auto", "cpu", "gpu", "bbox", "spans", "recompute")


def traverse(clip, faces, width, height, cull, offset, capacity, clip_cap, state, fn,
             traversal="auto", peel=True):
    """Run ``state = fn(state, chunk)`` over every work chunk of every triangle, clipped or not.

    Triangles that need no clipping come first, in submission order; triangles crossing a
    clip plane follow, clipped in chunks of ``clip_cap``. Needs 64-bit types enabled.
    Returns (state, counts) with counts of work items (bounding-box pixels, whichever
    traversal runs), clipped and non-finite triangles. ``traversal``: "auto" runs "cpu" or
    "gpu" by the platform the program is lowered for; "cpu": spans, or bounding boxes below
    SPANS_MIN_PIXELS; "gpu": per-item setup ("recompute") where triangles are dense, else
    bounding boxes, first chunk peeled and the clip chunks in the coverage loop; or one of
    ``coverage.TRAVERSALS`` everywhere (test hooks). ``peel="first"``: "gpu" runs the first
    chunk unconditionally, the other chunks and the clip chunks in two plain loops, for a
    state too large to pass through the conditional that joins them (XLA copies the state
    into and out of it at every step); ``peel=False``: every chunk in the loop. Each clip
    chunk covers its fans with the same peel, so with any peel it runs one chunk of their
    items, masked if they cover nothing."""
    if traversal not in TRAVERSALS:
        raise ValueError(f"traversal must be one of {TRAVERSALS}, got {traversal!r}")
    if traversal == "auto":
        def on(platform):
            return lambda c, f, o, st: traverse(c, f, width, height, cull, o, capacity,
                                                clip_cap, st, fn, platform, peel)

        return jax.lax.platform_dependent(clip, faces, offset, state, cpu=on("cpu"),
                                          default=on("gpu"))
    n_tris = faces.shape[0]
    guard = guard_band(width, height)
    peel = peel if traversal == "gpu" else False
    if traversal == "cpu":
        traversal = "bbox" if width * height < SPANS_MIN_PIXELS else "spans"
    elif traversal == "gpu":
        traversal = "recompute" if n_tris * RECOMPUTE_MIN_DENSITY >= width * height else "bbox"
    if traversal == "spans" and offset.ndim == 2:
        traversal = "bbox"  # spans are exact for one sample position only

    setup = SetupFn(width, height, cull)
    with jax.named_scope("classify"):
        # clip[faces] is gathered where it is used (fused), never stored.
        finite = jnp.all(jnp.isfinite(clip[faces]), axis=(1, 2))
        source = Triangles(clip, faces, finite, jnp.arange(n_tris, dtype=jnp.int32))
        inside, crossing = classify(source.gather()[0], guard)
        inside, crossing = inside & finite, crossing & finite
        # From a materialised copy, as dropped_nonfinite below (12 us at 1080p, 2.5k triangles).
        n_cross = jnp.sum(jax.lax.optimization_barrier(crossing), dtype=jnp.int64)

    def clip_fans(k):
        """The fans of the crossing triangles of rank k*clip_cap ... (k+1)*clip_cap-1."""
        with jax.named_scope("clip"):
            idx, _ = compact_indices(crossing, clip_cap, start=k * clip_cap)
            live = jnp.arange(clip_cap) < n_cross - k * clip_cap
            fan, fan_ok = clip_triangles(source.gather(idx)[0], guard)
            fan_ok = (fan_ok & live[:, None]).reshape(-1)
            n_fan = fan_ok.shape[0]
            return Triangles(fan.reshape(-1, 4), jnp.arange(3 * n_fan, dtype=jnp.int32)
                             .reshape(n_fan, 3), fan_ok, jnp.repeat(idx, MAX_FAN))

    def clip_chunk(k, carry):
        st, items = carry
        with jax.named_scope("coverage"):
            st, n = for_each_chunk(clip_fans(k), setup, capacity, offset, st, fn, traversal,
                                   peel)
        return st, items + n

    # The first clip chunk's fans follow the unclipped triangles in one list, so a frame whose
    # items fit one chunk runs no loop step (on a GPU each step and each loop's last test wait
    # for the host); further clip chunks, possible only when the chunk holds fewer than all
    # triangles, run as the coverage loop's ``then``.
    joined = dataclasses.replace(source, ok=inside).joined(clip_fans(0))
    then = None
    if clip_cap < n_tris:
        n_clip_chunks = (n_cross + clip_cap - 1) // clip_cap
        then = (jnp.maximum(n_clip_chunks - 1, 0), lambda k, carry: clip_chunk(k + 1, carry))
    with jax.named_scope("coverage"):
        state, items = for_each_chunk(joined, setup, capacity, offset, state, fn, traversal,
                                      peel, then=then)
    counts = {
        "work_items": items,
        "clipped": n_cross,
        # Summed from a materialised copy of the mask: otherwise XLA GPU fuses this scalar sum
        # with the triangle setup, which then runs inside the reduction's one thread block.
        "dropped_nonfinite": jnp.sum(~jax.lax.optimization_barrier(finite), dtype=jnp.int64),
    }
    return state, counts


def sample_visibility(clip, faces, width, height, offset, *, cull_backfaces=False,
                      work_capacity, clip_capacity, traversal="auto", barycentrics=True,
                      keep=None, live=None):
    """The nearest fragment of every pixel at one sample point, or at S sample points in one
    traversal: the per-sample core of every rasterizing entry, for use inside a program (no
    input checks).

    ``offset``: int64[2] (or int32[2]) fixed-point sample offset inside the pixel; or [S, 2]:
    every work item tests all S (the union of their bounding boxes is traversed once), and
    each sample's buffer is the one it gets alone, bit for bit, with a leading S axis on every
    field. ``live``: bool[S], the samples to keep (a dead sample covers nothing and counts no
    fragment; its offset should be a live one's, so that it widens no box). ``keep``: an
    optional ``keep(chunk) -> (bool[capacity] (or bool[S, capacity]), int tests run)`` that
    discards covered fragments before the depth test (a per-sample alpha test); discarded
    fragments still count in ``fragments``, and the tests it says it ran in ``keep_tests``.
    Returns (VisBuffer, or DepthBuffer without ``barycentrics``, with empty counts; counts dict
    of int64: work_items (bounding-box pixels, each testing every sample), clipped,
    dropped_nonfinite, fragments, and keep_tests with ``keep``)."""
    with jax.enable_x64(True):
        offset = offset.astype(jnp.int64)
        n_pix = width * height
        n_samples = 1 if offset.ndim == 1 else offset.shape[0]

        def scatter_min(st, c):
            zb, frags, tests = st
            covered, pix, tri, depth = flat_samples(c, width, height, live)
            hit = covered
            if keep is not None:
                kept, ran = keep(c)
                hit = covered & jnp.broadcast_to(kept, c.covered.shape).reshape(-1)
                tests = tests + ran.astype(jnp.int64)
            pix = jnp.where(hit, pix, n_samples * n_pix)
            zb = zb.at[pix].min(depth_key(depth, tri), mode="drop")
            return zb, frags + jnp.sum(covered, dtype=jnp.int64), tests

        zbuf = jnp.full((n_samples * n_pix,), EMPTY_KEY, jnp.int64)
        (zbuf, frags, tests), counts = traverse(
            clip, faces, width, height, cull_backfaces, offset, work_capacity, clip_capacity,
            (zbuf, jnp.int64(0), jnp.int64(0)), scatter_min, traversal,
        )
        with jax.named_scope("resolve"):
            off_px = offset.astype(jnp.float32) / (1 << SUBPIXEL_BITS)

            def one(zb, off):
                if not barycentrics:
                    return DepthBuffer(*decode_keys(zb, width, height))
                return resolve(zb, clip, faces, width, height, off)

            if offset.ndim == 1:
                vis = one(zbuf, off_px)
            else:
                vis = jax.vmap(one)(zbuf.reshape(n_samples, n_pix), off_px)
        counts = dict(counts, fragments=frags)
        if keep is not None:
            counts["keep_tests"] = tests
        return vis, counts


def _rasterize_x64(clip, faces, width, height, cull, offsets, capacity, clip_cap,
                   traversal="auto", barycentrics=True) -> VisBuffer | DepthBuffer:
    # Fixed-point offsets inside the pixel: int64[2] for one sample, else int64[S, 2], all
    # tested in one traversal at each bounding-box pixel.
    offs = jnp.asarray(offsets, jnp.int64)
    vis, counts = sample_visibility(clip, faces, width, height,
                                    offs[0] if len(offsets) == 1 else offs, cull_backfaces=cull,
                                    work_capacity=capacity, clip_capacity=clip_cap,
                                    traversal=traversal, barycentrics=barycentrics)
    return dataclasses.replace(vis, counts=Counts.pack(counts))
