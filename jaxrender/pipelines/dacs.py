"""DACS, deferred adaptive compute shading (Mallett and Yuksel, HPG 2018).

Sampling plan: the levels of ``dacs_levels`` inside each s x s block (s = 4: five levels;
s = 8: seven). Level 0 is always shaded. At each later level a pixel is shaded when its four
parents (on earlier levels, already final) are dissimilar: a parent's surface id (triangle,
object or material, from the full-resolution visibility buffer) differs from the pixel's own,
or the variance of the parents' luma is at or above ``threshold``. Otherwise the pixel is the
average of its parents.

Work: each level's pixels to shade are compacted and shaded through the shared chunked
dispatch, so the compiled program evaluates the shader only for them. The decisions also drive
``dacs_warp``'s simulation of the paper's SEARCH/SHADE warp scheme.

Borders: parents outside the image are left out of the test and of the average. The average
is over the opposite parent pairs that lie wholly inside the image, so a linear ramp is
reproduced exactly wherever such a pair exists (every pixel when W and H are 1 mod s). A pixel
with no complete pair inside (the last columns or rows of a partial block) takes the mean of
its parents inside (``border="average"``, the default: 1/16 of a 4k x 4k flat image is
shaded) or is always shaded (``border="shade"``: exact for a ramp at any size). Every pixel
beyond level 0 has a parent inside, so no size, odd or 1 pixel wide, gives a NaN.

The threshold is a traced config field (``TRACED_FIELDS``): a threshold sweep compiles once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.fusion import any_small, sum_small
import jaxrender.pipelines.dacs_warp as dacs_warp
import jaxrender.pipelines.dispatch as dispatch
from jaxrender.pipelines.base import BlendingConfig, make_counts, poison_on_overflow
from jaxrender.pipelines.dacs_levels import SPACINGS, level_map, level_pixels, parent_pairs
from jaxrender.pipelines.gbuffer import shade_through
from jaxrender.pipelines.pixel_ids import ID_KINDS, LUMAS, SPACES, check_choice, luma, surface_ids
from jaxrender.pipelines.registry import REGISTRY, register_frame
from jaxrender.pipelines.vertex_work import vertex_counts
from jaxrender.pipelines.transparency import merge_counts, transparent_pass
from jaxrender.pipelines.visibility import points_from_vis, share_visibility, visibility
from jaxrender.types import Array, Frame

BORDERS = ("average", "shade")


@dataclass(frozen=True)
class DacsConfig(BlendingConfig):
    """threshold: luma variance at or above which parents are dissimilar (0: shade everything;
    inf: ids alone decide). spacing: initial spacing 4 (five levels) or 8 (seven).
    ids: which surface id separates parents: triangle, object, material or none.
    luma: ``simple`` (0.25R + 0.5G + 0.25B) or ``rec709``; variance_space: luma of the
    ``display`` (clamped, sRGB-encoded) or ``linear`` colour.
    warp_width, warp_batches: the simulated warp (32 or 64 lanes) and the groups of W pixels
    each warp searches per level. border: ``average`` or ``shade`` pixels that lack a complete
    opposite pair of parents inside the image (see the module docstring); when width - 1 and
    height - 1 are multiples of the spacing every pixel has such a pair, and a non-default
    border is refused. chunk (see PipelineConfig; 0: 4096 lanes; each level is one launch of
    the fewest power-of-two number of chunks that holds its list) is not output-neutral here:
    the counts ``dispatch_lanes`` (chunks x chunk launched) and ``dispatch_chunks`` are read
    off it."""

    threshold: float = 0.01
    spacing: int = 4
    ids: str = "object"
    luma: str = "simple"
    variance_space: str = "display"
    warp_width: int = 32
    warp_batches: int = 4
    border: str = "average"

    TRACED_FIELDS: ClassVar[tuple[str, ...]] = ("threshold",)
    # Not ``chunk``: counts["dispatch_lanes"] (chunks x chunk launched) depends on it.
    OUTPUT_NEUTRAL: ClassVar[tuple[str, ...]] = ("fragment_capacity",)

    def __post_init__(self):
        super().__post_init__()
        if not float(self.threshold) >= 0.0:
            raise ValueError(f"threshold must be >= 0, got {self.threshold}")
        check_choice("spacing", self.spacing, SPACINGS)
        check_choice("ids", self.ids, ID_KINDS)
        check_choice("luma", self.luma, tuple(LUMAS))
        check_choice("variance_space", self.variance_space, SPACES)
        check_choice("border", self.border, BORDERS)
        check_choice("warp_width", self.warp_width, dacs_warp.WARP_WIDTHS)
        if int(self.warp_batches) < 1:
            raise ValueError(f"warp_batches must be >= 1, got {self.warp_batches}")
        # Nothing accepted and ignored: every pixel has a complete opposite pair of parents
        # inside the image exactly when W - 1 and H - 1 are multiples of the spacing.
        s = int(self.spacing)
        if self.border != type(self).border and (self.width - 1) % s == 0 \
                and (self.height - 1) % s == 0:
            raise ValueError(f"border = {self.border!r} has no effect at {self.width}x"
                             f"{self.height} with spacing {s}: every pixel has a complete "
                             f"opposite pair of parents inside the image")


def level_parents(pix: Array, level: int, h: int, w: int, spacing: int):
    """The parents of a level's flat pixels ``pix`` int32[n] (``level`` >= 1), computed in the
    program rather than stored as constants of it: indices int32[n, 4] (clamped), ``ins``
    bool[n, 4] (inside the image), averaging weights float32[n, 4] over the opposite pairs
    lying wholly inside (else over the parents inside), ``cnt`` float32[n] (parents inside, at
    least 1) and ``pair`` bool[n] (a complete opposite pair is inside)."""
    offsets = [o for pair in parent_pairs(level, spacing) for o in pair]
    py = (pix // w)[:, None] + jnp.asarray([[dy for dy, _ in offsets]], jnp.int32)
    px = (pix % w)[:, None] + jnp.asarray([[dx for _, dx in offsets]], jnp.int32)
    ins = (py >= 0) & (py < h) & (px >= 0) & (px < w)
    pidx = jnp.clip(py, 0, h - 1) * w + jnp.clip(px, 0, w - 1)
    pair_ok = jnp.stack([ins[:, 0] & ins[:, 1], ins[:, 2] & ins[:, 3]], axis=1)
    pair = pair_ok[:, 0] | pair_ok[:, 1]
    # No complete pair: the parents that are inside (every pixel past level 0 has one).
    wts = jnp.where(pair[:, None], jnp.repeat(pair_ok, 2, axis=1), ins).astype(jnp.float32)
    wts = wts / jnp.maximum(jnp.sum(wts, axis=1, keepdims=True), 1.0)
    cnt = jnp.maximum(jnp.sum(ins, axis=1), 1).astype(jnp.float32)
    return pidx, ins, wts, cnt, pair


def dacs_reconstruct(shade_fn: Callable[[Array, Array], Array], ids: Array, covered: Array,
                     threshold: Array, *, spacing: int = 4, luma_kind: str = "simple",
                     space: str = "display", chunk: int = 0, warp_width: int = 32,
                     warp_batches: int = 4, border: str = "average"):
    """The DACS plan and reconstruction over any shading function.

    ``shade_fn(pixels int32[c], live bool[c]) -> float32[c, 3]`` shades flat pixel indices;
    ``ids`` int32[H, W] surface ids (-1 uncovered); ``covered`` bool[H, W] (uncovered pixels are
    never shaded and come out 0); ``border`` as DacsConfig. The levels run one after another,
    unrolled in the program, each over its own pixels (``level_pixels``): a level's pixels are
    independent, as every parent lies on an earlier level. Each level compacts its pixels to
    shade into a work list and dispatches it in chunks.
    Returns (image float32[H, W, 3], shaded bool[H, W], level int32[H, W], counts)."""
    h, w = ids.shape
    n_pix = h * w
    ids_f = ids.reshape(-1)
    cov_f = covered.reshape(-1)
    thr = jnp.asarray(threshold, jnp.float32)
    # Each level is one launch of the fewest power-of-two MIN_CHUNK-lane chunks that hold its
    # list (dispatch's "switch"): a loop of such chunks paid a host round trip per chunk (40-73
    # a frame), and a loop of the largest level's size (65536 lanes at 1920x1080) launched
    # four times the lanes DACS shades; benchmarks/RESULTS.md, ninth and twelfth sessions.
    level_chunk = int(chunk) if int(chunk) > 0 else dispatch.MIN_CHUNK  # run() caps it at the list

    def decide_and_interpolate(level, pix, cov, img):
        pidx, ins, wts, cnt, pair = level_parents(pix, level, h, w, spacing)
        c = img[pidx]  # [n, 4, 3] parents, final from earlier levels
        with jax.named_scope("decide"):
            id_diff = any_small(ins & (ids_f[pidx] != ids_f[pix][:, None]), axis=1)
            lum = luma(c, luma_kind, space)  # [n, 4]
            insf = ins.astype(jnp.float32)
            mean = sum_small(insf * lum, axis=1) / cnt
            var = sum_small(insf * (lum - mean[:, None]) ** 2, axis=1) / cnt
            no_pair = ~pair if border == "shade" else jnp.zeros_like(cov)
            need = cov & (no_pair | id_diff | (var >= thr))
        with jax.named_scope("interpolate"):
            interp = sum_small(wts[:, :, None] * c, axis=1)
            val = jnp.where((cov & ~need)[:, None], interp, 0.0)
        return val, need

    img = jnp.zeros((n_pix, 3), jnp.float32)
    levels = level_pixels(h, w, spacing)
    needs, inv, lanes, chunks = [], jnp.int32(0), jnp.int32(0), jnp.int32(0)
    # Unrolled rather than a loop over steps padded to one size: on a GPU a loop reads back to
    # the host every iteration and decides over the padding too.
    for level, level_pix in enumerate(levels):
        if len(level_pix) == 0:  # an image too small for this level
            needs.append(jnp.zeros((0,), bool))
            continue
        pix = jnp.asarray(level_pix, jnp.int32)
        cov = cov_f[pix]
        if level == 0:  # always shaded
            need, val = cov, jnp.zeros((len(level_pix), 3), jnp.float32)
        else:
            val, need = decide_and_interpolate(level, pix, cov, img)
        with jax.named_scope("shade"):
            # Shaded into the level's own values, then the level written into the image once:
            # a launch that scattered into the image copied all of it (25 MB at 1080p) first.
            listed = dispatch.WorkList.of(need)
            val, work = dispatch.run(listed, lambda items, live: shade_fn(pix[items], live),
                                     val, level_chunk, default_mode="switch")
        img = img.at[pix].set(val, unique_indices=True)
        needs.append(need)
        inv, lanes, chunks = inv + work.invocations, lanes + work.lanes, chunks + work.chunks
    warp = dacs_warp.simulate(needs, warp_width, warp_batches)
    # Every pixel is in exactly one level.
    all_pix = np.concatenate(levels).astype(np.int32)
    shaded = jnp.zeros((n_pix,), bool).at[all_pix].set(jnp.concatenate(needs),
                                                        unique_indices=True)
    counts = {"shade_invocations": inv, "dispatch_lanes": lanes, "dispatch_chunks": chunks,
              "covered_pixels": jnp.sum(covered, dtype=jnp.int32), **warp}
    level = jnp.asarray(level_map(h, w, spacing))
    return img.reshape(h, w, 3), shaded.reshape(h, w), level, counts


@register_frame("dacs", DacsConfig)
def frame(scene, camera, cfg: DacsConfig) -> Frame:
    """DACS: five (seven) levels per block, shade where parents differ, else interpolate."""
    with jax.named_scope("visibility"):
        vis = visibility(scene, camera, cfg)
        covered = vis.tri_id >= 0
        ids = surface_ids(scene, vis.tri_id, cfg.ids)

    def shade_fn(items, live):
        # The deferred lighting pass's own path on the attributes of just these pixels: DACS is
        # deferred shading with an adaptive plan.
        return shade_through(points_from_vis(scene, camera, vis, items), scene, camera, live)

    with jax.named_scope("dacs"):
        image, shaded, level, c = dacs_reconstruct(
            shade_fn, ids, covered, cfg.threshold, spacing=cfg.spacing, luma_kind=cfg.luma,
            space=cfg.variance_space, chunk=cfg.chunk, warp_width=cfg.warp_width,
            warp_batches=cfg.warp_batches, border=cfg.border)
    image, blended = transparent_pass(scene, camera, image, vis.depth, cfg)
    warps = c.pop("warps")
    counts = make_counts(waves=warps, lane_utilization=c["warp_lane_utilization"],
                         shaded_fraction=c["shade_invocations"].astype(jnp.float32)
                         / jnp.maximum(c["covered_pixels"], 1).astype(jnp.float32),
                         alpha_invocations=vis.counts["alpha_invocations"],
                         overflow=vis.counts["overflow"], **c,
                         **vertex_counts(scene, full_passes=1))  # the raster pass
    counts = merge_counts(counts, blended)
    image = poison_on_overflow(image, counts["overflow"])
    return Frame(image, counts, share_visibility({"level": level, "shaded": shaded}, vis, cfg))

render = REGISTRY["dacs"].render  # the compiled, overflow-checked entry
