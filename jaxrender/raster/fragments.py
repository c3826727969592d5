"""Every covered (pixel, triangle, depth): the input of pipelines that model overdraw.

Fragments are written in traversal order: triangles that need no clipping in submission
order, then the clipped ones; each carries its triangle index, which is its submission order,
so a pipeline sorts by (pixel, triangle) to replay the draw. The list has a static capacity.
It never drops silently: ``count`` is the true number of fragments even past the capacity, and
the eager entry raises an error naming ``capacity`` when it overflows; under an outer jit the
caller checks ``overflowed`` (pipelines report it in their counts).
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp

import jaxrender.raster.samples as sample_patterns
from jaxrender.raster.checks import check_mesh, check_size
from jaxrender.raster.rasterize import default_clip_capacity, default_work_capacity, traverse
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.raster.work_items import flat_samples
from jaxrender.types import Array, pytree_dataclass


@pytree_dataclass
class Fragments:
    """pixel int32[F] (row-major index y * W + x), tri int32[F], depth float32[F], valid bool[F],
    count int32[] (all fragments, possibly more than F)."""

    pixel: Array
    tri: Array
    depth: Array
    valid: Array
    count: Array

    @property
    def overflowed(self) -> Array:
        return self.count > self.pixel.shape[0]


def default_fragment_capacity(width: int, height: int) -> int:
    return 4 * width * height


def fragments(
    clip: Array,
    faces: Array,
    width: int,
    height: int,
    *,
    capacity: int | None = None,
    cull_backfaces: bool = False,
    sample_offset=(0.5, 0.5),
    work_capacity: int | None = None,
    clip_capacity: int | None = None,
) -> Fragments:
    """All covered (pixel, triangle, depth) of clip-space triangles; see the module docstring."""
    width, height = check_size(width, height)
    check_mesh(clip, faces, "clip", 4)
    (offset,) = sample_patterns.to_fixed(sample_patterns.validate([sample_offset]), SUBPIXEL_BITS)
    cap = int(capacity or default_fragment_capacity(width, height))
    frags = fragments_jit(
        jnp.asarray(clip, jnp.float32),
        jnp.asarray(faces, jnp.int32),
        width=width,
        height=height,
        capacity=cap,
        cull_backfaces=bool(cull_backfaces),
        offset=offset,
        work_capacity=int(work_capacity or default_work_capacity(faces.shape[0], width, height)),
        clip_capacity=int(clip_capacity or default_clip_capacity(faces.shape[0])),
    )
    if not isinstance(frags.count, jax.core.Tracer) and bool(frags.overflowed):
        raise OverflowError(
            f"fragments: {int(frags.count)} fragments exceed capacity={cap}; "
            f"pass capacity>={int(frags.count)}"
        )
    return frags


@partial(
    jax.jit,
    static_argnames=(
        "width", "height", "capacity", "cull_backfaces", "offset", "work_capacity",
        "clip_capacity", "traversal",
    ),
)
def fragments_jit(
    clip, faces, *, width, height, capacity, cull_backfaces, offset, work_capacity, clip_capacity,
    traversal="auto",
) -> Fragments:
    """The jitted core of ``fragments`` (no input checks); ``traversal`` as ``raster.traverse``."""
    return collect_fragments(clip, faces, width, height, capacity, cull_backfaces,
                             jnp.asarray(offset, jnp.int32), work_capacity, clip_capacity,
                             traversal)


def collect_fragments(clip, faces, width: int, height: int, capacity: int, cull_backfaces: bool,
                      offset: Array, work_capacity: int, clip_capacity: int,
                      traversal: str = "auto", live: Array | None = None) -> Fragments:
    """``fragments_jit`` for use inside a program, at a fixed-point sample ``offset`` int32[2]
    that may be traced (the reference's per-sample loop). With offsets int32[S, 2] the samples
    share one traversal and one list: sample s of pixel p is ``pixel`` s * W * H + p, and each
    sample's fragments keep the order of its own list. ``live`` bool[S]: the samples to list
    (a dead sample's offset should repeat a live one's, so that it widens no bounding box)."""
    with jax.enable_x64(True):
        def append(st, c):
            pix, tri, depth, n = st
            # Sample-major, so that each sample's entries keep their order.
            covered, at_pixel, tri_c, depth_c = flat_samples(c, width, height, live)
            pos = n + jnp.cumsum(covered, dtype=jnp.int64) - 1
            at = jnp.where(covered & (pos < capacity), pos, capacity)
            pix = pix.at[at].set(at_pixel, mode="drop")
            tri = tri.at[at].set(tri_c, mode="drop")
            depth = depth.at[at].set(depth_c, mode="drop")
            return pix, tri, depth, n + jnp.sum(covered, dtype=jnp.int64)

        init = (
            jnp.zeros((capacity,), jnp.int32),
            jnp.full((capacity,), -1, jnp.int32),
            jnp.ones((capacity,), jnp.float32),
            jnp.int64(0),
        )
        (pix, tri, depth, n), _ = traverse(
            clip, faces, width, height, cull_backfaces, offset.astype(jnp.int64),
            work_capacity, clip_capacity, init, append, traversal,
            peel="first",  # three capacity-sized lists: a cond in the loop would copy them
        )
        valid = jnp.arange(capacity) < n
        return Fragments(pix, tri, depth, valid, n.astype(jnp.int32))
