"""The ground truth: k x k stratified sub-pixel samples per pixel, each shaded, box-filtered.

Sampling plan: every pixel is split into k x k cells and each cell centre is a visibility
sample of its own (the rasterizer's exact coverage at that sub-pixel offset); every covered
sample is a surface point shaded by the shared ``shade()`` at its own position, with texture
LOD from the sample's footprint (the barycentric derivatives per pixel scaled by 1/k, i.e. per
sample spacing). Reconstruction: the box filter, the mean of the k^2 sample colours (empty
samples count as black background).

Passes: the samples run a few at a time (``samples_per_pass``, 8 by default) in a
``lax.fori_loop`` that accumulates the image. A pass rasterizes its samples in one traversal
(each bounding-box pixel of a triangle tests every sample of the pass, each sample's result
the one it gets alone) and shades all their covered points in one launch, so a pass's loops,
launches and bounding boxes serve all of its samples. The peak memory is one pass's visibility
buffers and shading (at most 2^24 lanes by default), whatever k is, not k^2 buffers.

Alpha-tested scenes (``effects.alpha_test``): a fragment that fails the alpha test at its
sample position is discarded before the depth test, so the sample sees what lies behind it.

``convergence_psnr`` renders at k and 2k and returns their LDR PSNR, the estimate a study sets
beside its best pipeline: a reference converged well (10 dB or more) above the pipelines
it judges measures their error, not its own.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import jax
import jax.numpy as jnp

import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.reference_transparent import sample_pass
from jaxrender.pipelines.registry import REGISTRY, RenderConfig, register_frame
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.visibility import is_alpha_tested, opaque_faces
from jaxrender.raster.rasterize import (default_clip_capacity, default_work_capacity,
                                        sample_visibility)
from jaxrender.raster.resolve import barycentrics_at, barycentrics_from_rows, triangle_rows
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene.camera import Camera, world_to_clip
from jaxrender.scene.scene import Scene
from jaxrender.shading import alpha_test, shade, surface_points
from jaxrender.shading.srgb import srgb_encode
from jaxrender.types import Array, Frame

# Chosen from the convergence check (python benchmarks/bench_reference.py --convergence
# --scenes all --width 96 --height 64 --k 2 4 8 16): PSNR(k, 2k) in LDR dB at k = 8 was
# stripes 41.1, spheres 51.9, foliage 43.7, thin 33.7, terrain 57.3, sliver 55.1, room 49.3,
# many_small 54.4; at k = 16 every scene is >= 46 dB (thin 46.3, the rest 50-68). k = 8 is
# converged >= 40 dB except for sub-pixel wires aligned with the pixel grid (thin), where the
# regular grid of cell centres converges in steps: studies of such scenes should set k = 16.
DEFAULT_K = 8


@dataclass(frozen=True)
class ReferenceConfig(RenderConfig):
    """k: samples per pixel side (k x k stratified cell centres); chunk: shading work-list
    chunk size (0: one launch a pass, of its covered samples compacted into half its lanes
    when at most half are covered, else of all of them in place: a pass's covered samples are
    often most of its screens, and 64 samples times several launches each cost more in
    launches than the idle lanes of one; it shows in the dispatch counts lanes, chunks and
    helper_lanes);
    convergence: also render at
    2k and report ``counts['convergence_psnr']`` (LDR PSNR between the k and 2k images; costs
    5x the plain render); samples_per_pass: samples rasterized in one traversal and shaded in
    one launch (0: automatic, up to 8 and 2^24 lanes a pass). The image is the same for any
    value; lanes, chunks and work_items follow the passes."""

    k: int = DEFAULT_K
    chunk: int = 0
    convergence: bool = False
    samples_per_pass: int = 0

    TRACED_FIELDS: ClassVar[tuple[str, ...]] = ("k",)
    # Not ``chunk`` nor ``samples_per_pass``: counts["lanes"], ["chunks"] and ["helper_lanes"]
    # (the idle lanes of the last chunk of each pass) are read off the dispatch and depend on
    # them, and ["work_items"] on the passes.
    OUTPUT_NEUTRAL: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self):
        super().__post_init__()
        if int(self.k) < 1:
            raise ValueError(f"reference: k must be >= 1, got {self.k}")
        if int(self.chunk) < 0:
            raise ValueError(f"reference: chunk must be >= 0 (0: automatic), got {self.chunk}")
        if int(self.samples_per_pass) < 0:
            raise ValueError("reference: samples_per_pass must be >= 0 (0: automatic), got "
                             f"{self.samples_per_pass}")


# ------------------------------------------------------------------ visibility of one sample

# The alpha test's launch: a quarter of a traversal chunk's lanes (items times samples); the
# covered samples of alpha-tested triangles are a fraction of a chunk's box pixels.
ALPHA_CHUNKS = 4


def _bary_at(tri: Array, x: Array, y: Array, clip: Array, faces: Array, w: int, h: int):
    """Barycentrics and their per-pixel derivatives at window points: the rasterizer's own."""
    bary, ddx, ddy, _ = barycentrics_at(tri, x, y, clip, faces, w, h)
    return bary, ddx, ddy


def _visibility(scene: Scene, camera: Camera, clip: Array, offsets: Array, live: Array, cfg,
                inv_k: Array):
    """DepthBuffers [S, H, W] (ids and depths) of S samples at the traced fixed-point offsets
    int32[S, 2], in one traversal; fragments failing the alpha test are discarded before the
    depth test. Returns (vis, counts)."""
    w, h = cfg.width, cfg.height
    faces = scene.faces
    n_tris = faces.shape[0]
    off_px = offsets.astype(jnp.float32) / (1 << SUBPIXEL_BITS)

    def alpha_keep(c):  # c.covered: [S, capacity]
        # Only the covered live samples of alpha-tested triangles run the test, compacted: a
        # chunk's lanes are every bounding-box pixel times every sample of the pass, most of
        # them uncovered, and the test (barycentrics, surface point, a texture fetch) costs
        # about what shading does.
        n_s, cap = c.covered.shape
        tested = (c.covered & live[:, None] & is_alpha_tested(scene, c.tri)[None]).reshape(-1)

        def points_of(items):
            s, i = items // cap, items % cap
            tri = c.tri[i]
            x = c.px[i].astype(jnp.float32) + off_px[s, 0]
            y = c.py[i].astype(jnp.float32) + off_px[s, 1]
            b, bx, by = _bary_at(tri, x, y, clip, faces, w, h)
            return surface_points(scene, camera, tri, b, bx * inv_k, by * inv_k)

        with jax.enable_x64(False):
            passed, work = dispatch.shade(
                dispatch.WorkList.of(tested), points_of,
                lambda pts: alpha_test(pts, scene).astype(jnp.float32),
                jnp.ones((n_s * cap,), jnp.float32), max(n_s * cap // ALPHA_CHUNKS, 1))
        return passed.reshape(n_s, cap) > 0.5, work.invocations

    vis, counts = sample_visibility(
        clip, opaque_faces(scene), w, h, offsets, work_capacity=default_work_capacity(n_tris, w, h),
        clip_capacity=default_clip_capacity(n_tris), live=live, barycentrics=False,
        keep=alpha_keep if scene.effects.alpha_test else None)
    return vis, {key: v.astype(jnp.int32) for key, v in counts.items()}


# ------------------------------------------------------------------ the render

# The transparent pass's counts summed over the passes (the layers' maximum is a maximum;
# transparent_passes counts blending passes, each blending one layer of every sample of a pass).
TRANSPARENT_SUMS = ("transparent_invocations", "transparent_fragments", "transparent_passes",
                    "transparent_bytes", "overflow")
RUNNING_MAXIMA = ("transparent_layers_max",)

# Samples rasterized and shaded together, at most: a pass's loops, launches and bounding-box
# items serve all of them. The automatic choice also keeps a pass within LANES_PER_PASS
# shading lanes (8 at 1920x1080), which bounds its memory.
MAX_SAMPLES_PER_PASS = 8
LANES_PER_PASS = 1 << 24


def samples_per_pass(cfg: ReferenceConfig) -> int:
    """The samples of one pass: cfg.samples_per_pass, or automatic for 0."""
    if cfg.samples_per_pass:
        return int(cfg.samples_per_pass)
    return max(1, min(MAX_SAMPLES_PER_PASS, LANES_PER_PASS // (cfg.width * cfg.height)))


def _offset(s: Array, k: Array) -> Array:
    """int32[2, ...]: fixed-point offset of stratified sample s (row-major) of k x k, computed
    in integers: round((i + 0.5) / k * 2^bits) = floor(((2i + 1) 2^bits + k) / 2k), as
    ``samples.to_fixed(samples.stratified(k))`` gives."""
    i, j = s % k, s // k
    one = 1 << SUBPIXEL_BITS
    return jnp.stack([((2 * i + 1) * one + k) // (2 * k), ((2 * j + 1) * one + k) // (2 * k)])


def _shade_samples(covered, points_of, shade_fn, out, chunk: int):
    """A pass's covered samples shaded: in one launch by default (chunk 0; compacted into half
    the pass's lanes when at most half are covered, else in place: ``dispatch.shade_dense``),
    else through the compacted dispatch in chunks of ``chunk``."""
    if chunk == 0:
        return dispatch.shade_dense(covered, points_of, shade_fn, out)
    return dispatch.shade(dispatch.WorkList.of(covered), points_of, shade_fn, out, chunk)


def _accumulate(counts: dict, new: dict) -> dict:
    return {key: jnp.maximum(counts[key], new[key]) if key in RUNNING_MAXIMA
            else counts[key] + new[key] for key in counts}


def _render(scene: Scene, camera: Camera, k: Array, cfg: ReferenceConfig) -> Frame:
    """The reference image at k x k samples per pixel; k is traced (int32[]), so every k
    shares one compiled program. Only cfg's width, height, chunk and samples_per_pass are
    used. The samples run in passes of ``samples_per_pass(cfg)``; a last pass with fewer
    samples left runs its extra samples dead (counted in lanes, not in invocations)."""
    w, h = cfg.width, cfg.height
    n_pix = w * h
    n_s = samples_per_pass(cfg)
    with jax.named_scope("transform"):
        clip = world_to_clip(scene.positions, camera, w / h)
        rows = triangle_rows(clip, scene.faces)
    inv_k = 1.0 / k.astype(jnp.float32)

    def one_pass(p, carry):
        acc, any_cov, counts = carry
        s = p * n_s + jnp.arange(n_s)
        live = s < k * k
        offsets = _offset(jnp.where(live, s, p * n_s), k).T  # a dead sample repeats a live one
        off_px = offsets.astype(jnp.float32) / (1 << SUBPIXEL_BITS)
        with jax.named_scope("raster"):
            vis, rc = _visibility(scene, camera, clip, offsets, live, cfg, inv_k)
        tri = vis.tri_id.reshape(-1)

        def points_of(items):
            # Each sample's barycentrics computed where it is shaded: the pass keeps ids and
            # depths only, and a compacted launch computes its covered samples' alone.
            t, sample = tri[items], items // n_pix
            q = items - sample * n_pix
            x = (q % w).astype(jnp.float32) + off_px[sample, 0]
            y = (q // w).astype(jnp.float32) + off_px[sample, 1]
            b, ddx, ddy = barycentrics_from_rows(rows, t, x, y, w, h)
            # inv_k: the footprint of one sample, not one pixel
            return surface_points(scene, camera, t, b, ddx * inv_k, ddy * inv_k)

        with jax.named_scope("shade"):
            rgb, work = _shade_samples(tri >= 0, points_of, lambda p: shade(p, scene),
                                       jnp.zeros((n_s * n_pix, 3), jnp.float32), cfg.chunk)
        new = {"shade_invocations": work.invocations, "lanes": work.lanes,
               "chunks": work.chunks, "fragments": rc["fragments"],
               "work_items": rc["work_items"],
               "alpha_invocations": rc.get("keep_tests", jnp.int32(0))}
        if scene.effects.transparency:  # every layer of each sample, sorted, over it
            with jax.named_scope("transparent"):
                rgb, tc = sample_pass(scene, camera, clip, offsets, live, vis.depth.reshape(-1),
                                      rgb, inv_k, cfg)
            new.update({key: tc[key] for key in TRANSPARENT_SUMS + RUNNING_MAXIMA})
            # The layers' dispatch is shading work like the opaque launch: in lanes and chunks.
            new["shade_invocations"] = new["shade_invocations"] + tc["transparent_invocations"]
            new["lanes"] = new["lanes"] + tc["transparent_lanes"]
            new["chunks"] = new["chunks"] + tc["transparent_chunks"]
        rgb = rgb.reshape(n_s, n_pix, 3)
        for t in range(n_s):  # sample by sample, in order: the sum of one sample per pass
            acc = acc + rgb[t]
        covered = jnp.any(tri.reshape(n_s, n_pix) >= 0, axis=0)
        return acc, any_cov | covered, _accumulate(counts, new)

    keys = ("shade_invocations", "lanes", "chunks", "fragments", "work_items", "alpha_invocations")
    if scene.effects.transparency:
        keys = keys + TRANSPARENT_SUMS + RUNNING_MAXIMA
    counts0 = {key: jnp.int32(0) for key in keys}
    init = (jnp.zeros((n_pix, 3), jnp.float32), jnp.zeros((n_pix,), bool), counts0)
    acc, any_cov, counts = jax.lax.fori_loop(0, (k * k + n_s - 1) // n_s, one_pass, init)
    with jax.named_scope("reconstruct"):
        image = (acc * (inv_k * inv_k)).reshape(h, w, 3)
    counts = dict(counts, covered_pixels=jnp.sum(any_cov, dtype=jnp.int32),
                  samples_per_pixel=k * k,
                  helper_lanes=counts["lanes"] - counts["shade_invocations"],
                  # One transform of every vertex serves all k x k sample rasterizations.
                  **vertex_counts(scene, full_passes=1))
    return Frame(image=image, counts=counts, aux={"coverage": any_cov.reshape(h, w)})


def ldr_psnr(a: Array, b: Array) -> Array:
    """PSNR in dB of the display-referred (clamped, sRGB-encoded) images, data range 1;
    over the trailing (H, W, 3) axes. +inf for identical images."""
    d = srgb_encode(jnp.clip(a, 0.0, 1.0)) - srgb_encode(jnp.clip(b, 0.0, 1.0))
    mse = jnp.mean(d * d, axis=(-3, -2, -1))
    return 10.0 * jnp.log10(1.0 / mse)


@register_frame("reference", ReferenceConfig,
                "ground truth: k x k stratified samples per pixel, each shaded, box filter")
def frame(scene: Scene, camera: Camera, cfg: ReferenceConfig) -> Frame:
    """Ground truth: k x k stratified samples per pixel, each shaded, box filter.

    k is a traced config field, so changing k or moving the camera never recompiles. With
    ``cfg.convergence`` the frame is rendered again at 2k and ``counts['convergence_psnr']``
    holds their LDR PSNR.
    """
    k = jnp.asarray(cfg.k, jnp.int32)
    frame = _render(scene, camera, k, cfg)
    if cfg.convergence:
        fine = _render(scene, camera, 2 * k, cfg)
        frame = replace(frame, counts=dict(frame.counts,
                                           convergence_psnr=ldr_psnr(frame.image, fine.image)))
    return frame

render = REGISTRY["reference"].render  # the compiled, overflow-checked entry

def convergence_psnr(scene: Scene, camera: Camera, cfg: ReferenceConfig) -> float:
    """LDR PSNR (dB) between the reference at k and at 2k samples per pixel side: how far the
    reference is from converged. A study wants it >= its best pipeline's PSNR + 10 dB."""
    frame = render(scene, camera, replace(cfg, convergence=True))
    return float(frame.counts["convergence_psnr"])
