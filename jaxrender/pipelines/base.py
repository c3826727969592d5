"""What every pipeline shares: the config base, the standard counts of a Frame and the NaN
image of a frame that overflowed.

A pipeline is made of stages, data in and data out: ``visibility`` (pipelines.visibility), a
plan that lists the points to shade as a ``WorkList``, ``dispatch.shade`` over it, and a
reconstruction into the image; its counts are read off the work lists (``waves.count_waves``
for the waves). It registers its ``step`` (or a stateless ``frame``) with the registry
(``registry.register`` / ``register_frame``); ``pipelines.program`` compiles and runs it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import jax.numpy as jnp

from jaxrender.pipelines.dispatch import DEFAULT_CHUNK
from jaxrender.pipelines.registry import RenderConfig
from jaxrender.types import Array

# Keys present in every Frame's counts (0 where a pipeline has no such notion).
INT_COUNTS = ("shade_invocations", "helper_lanes", "covered_pixels", "waves",
              "bytes_intermediate")
FLOAT_COUNTS = ("overshading", "lane_utilization")
COUNT_KEYS = INT_COUNTS + FLOAT_COUNTS


@dataclass(frozen=True)
class PipelineConfig(RenderConfig):
    """Settings shared by the raster-based pipelines.

    chunk: lanes per shading dispatch chunk (the DispatchIndirect group size of the work list);
        0 (the default) sizes it to the work list (``dispatch.auto_chunk``: about sixteen
        chunks for a full screen; DACS's levels: ``dispatch.MIN_CHUNK``; object space's store
        and TADS's texels: half a screen and a screen, not their capacity), except deferred's
        screen passes, which then launch once (``dispatch.shade_screen``), and the transparent
        pass, which then tests, shades and blends its list in one launch
        (``transparency.blend_on_prefix``).
    cull_backfaces: drop back-facing triangles in the rasterizer.
    fragment_capacity: size of the fragment list per sample (0 = 4 x width x height); a frame
        with more fragments reports ``overflow`` and, called eagerly, raises OverflowError.
    """

    chunk: int = DEFAULT_CHUNK
    cull_backfaces: bool = False
    fragment_capacity: int = 0

    OUTPUT_NEUTRAL: ClassVar[tuple[str, ...]] = ("chunk", "fragment_capacity")

    def __post_init__(self):
        super().__post_init__()
        if int(self.chunk) < 0:
            raise ValueError(f"chunk must be >= 0 (0: automatic), got {self.chunk}")
        if int(self.fragment_capacity) < 0:
            raise ValueError(f"fragment_capacity must be >= 0, got {self.fragment_capacity}")

    @property
    def capacity(self) -> int:
        return int(self.fragment_capacity or 4 * self.width * self.height)

    def overflow_hint(self) -> str:
        return (f"fragments past fragment_capacity={self.capacity}, or visibility ids that do "
                f"not fit their bit fields; raise fragment_capacity (see the Frame counts)")


TRANSPARENT_OVERFLOWS = ("chunks", "error")
OIT_MODES = ("sorted", "weighted")


@dataclass(frozen=True)
class BlendingConfig(PipelineConfig):
    """The settings of the transparent pass (``pipelines.transparency``), for the pipelines that
    run it; refused on a scene without the transparency effect.

    oit: "sorted" (exact: every pixel's layers sorted back to front) or "weighted" (weighted
        blended order-independent transparency, McGuire and Bavoil 2013: no sort, no cap).
    transparent_layers: the static cap of layers per pixel composited per pass (a k-buffer of
        that depth); a pixel with more runs further passes ("chunks") or the frame is refused
        naming the cap ("error"). Sorted only.
    transparent_overflow: "chunks" or "error", as above.
    """

    oit: str = "sorted"
    transparent_layers: int = 8
    transparent_overflow: str = "chunks"

    def __post_init__(self):
        super().__post_init__()
        if self.oit not in OIT_MODES:
            raise ValueError(f"oit must be one of {', '.join(OIT_MODES)}, got {self.oit!r}")
        if int(self.transparent_layers) < 1:
            raise ValueError(f"transparent_layers must be >= 1, got {self.transparent_layers}")
        if self.transparent_overflow not in TRANSPARENT_OVERFLOWS:
            raise ValueError(f"transparent_overflow must be one of "
                             f"{', '.join(TRANSPARENT_OVERFLOWS)}, got "
                             f"{self.transparent_overflow!r}")
        if self.oit == "weighted":
            for f in ("transparent_layers", "transparent_overflow"):
                if getattr(self, f) != BLENDING_DEFAULTS[f]:
                    raise ValueError(f"{f} has no effect with oit = \"weighted\" (no sort, no "
                                     f"layer cap); leave it or set oit = \"sorted\"")

    def overflow_hint(self) -> str:
        return (super().overflow_hint() + f"; or a pixel with more transparent layers than "
                f"transparent_layers={self.transparent_layers} under transparent_overflow = "
                f"\"error\" (raise the cap or use \"chunks\")")


BLENDING_DEFAULTS = {"oit": "sorted", "transparent_layers": 8, "transparent_overflow": "chunks"}


def make_counts(**values) -> dict:
    """The standard counts dict: every key of COUNT_KEYS (0 when not given) plus extras.
    ``overshading`` defaults to shade_invocations / covered_pixels."""
    out = {}
    for k in INT_COUNTS:
        out[k] = jnp.asarray(values.pop(k, 0)).astype(jnp.int32)
    inv = out["shade_invocations"].astype(jnp.float32)
    cov = out["covered_pixels"].astype(jnp.float32)
    default_over = inv / jnp.maximum(cov, 1.0)
    out["overshading"] = jnp.asarray(values.pop("overshading", default_over)).astype(jnp.float32)
    out["lane_utilization"] = jnp.asarray(values.pop("lane_utilization", 0.0)).astype(jnp.float32)
    for k, v in values.items():
        v = jnp.asarray(v)
        out[k] = v.astype(jnp.float32 if jnp.issubdtype(v.dtype, jnp.floating) else jnp.int32)
    return out


def poison_on_overflow(image: Array, overflow: Array) -> Array:
    """NaN everywhere when something overflowed: a frame with missing work must look broken."""
    return jnp.where(overflow > 0, jnp.float32(jnp.nan), image)


__all__ = ["BLENDING_DEFAULTS", "BlendingConfig", "COUNT_KEYS", "FLOAT_COUNTS", "INT_COUNTS",
           "PipelineConfig", "make_counts",
           "poison_on_overflow"]
