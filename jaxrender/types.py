"""The data that flows between stages: scene -> visibility -> shading -> image.

Every stage takes data and returns data. These containers are pytrees: array fields are
traced, fields marked static are hashable metadata. Leading batch axes are allowed on every
array field (samples ``(S, H, W)``, frames ``(T, H, W)``); shapes below give the trailing axes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp

Array = jax.Array


def pytree_dataclass(cls):
    """Frozen dataclass registered as a pytree; fields with metadata static=True are static."""
    cls = dataclass(frozen=True)(cls)
    data, meta = [], []
    for f in dataclasses.fields(cls):
        (meta if f.metadata.get("static", False) else data).append(f.name)
    return jax.tree_util.register_dataclass(cls, data_fields=data, meta_fields=meta)


def static_field(**kwargs):
    return field(metadata={"static": True}, **kwargs)


class Counts(Mapping):
    """Named integer scalars held as one array: a compiled program hands each output buffer
    back separately (microseconds each on a GPU), so a rasterizer called on its own
    returns its counts as one buffer. Reads like a dict (``counts["fragments"]``, ``dict(counts)``);
    outside a program each read is a small slice of the device array."""

    def __init__(self, names: tuple[str, ...], values):
        self.names, self.values = tuple(names), values

    @classmethod
    def pack(cls, counts: dict, dtype=jnp.int32) -> "Counts":
        names = tuple(counts)
        return cls(names, jnp.stack([jnp.asarray(counts[k]).astype(dtype) for k in names]))

    def __getitem__(self, key):
        try:
            i = self.names.index(key)
        except ValueError:
            raise KeyError(key) from None
        return self.values[..., i]

    def __iter__(self):
        return iter(self.names)

    def __len__(self) -> int:
        return len(self.names)

    def __repr__(self) -> str:
        if isinstance(self.values, jax.core.Tracer) or not hasattr(self.values, "tolist"):
            return f"Counts({self.names}, {type(self.values).__name__})"
        return f"Counts({dict(zip(self.names, self.values.T.tolist()))})"


jax.tree_util.register_pytree_node(
    Counts, lambda c: ((c.values,), c.names), lambda names, leaves: Counts(names, leaves[0]))


class _Ids:
    """``covered`` for the buffers that carry ``tri_id`` (-1 where empty)."""

    @property
    def covered(self) -> Array:
        return self.tri_id >= 0


@pytree_dataclass
class DepthBuffer(_Ids):
    """Per-pixel depth and visibility without barycentrics (``raster.rasterize_depth``): what a
    depth pre-pass, a shadow map or an id buffer needs.

    tri_id: int32[H, W]   as in VisBuffer (-1 where empty).
    depth:  float32[H, W] as in VisBuffer (1.0 where empty).
    counts: as in VisBuffer.
    """

    tri_id: Array
    depth: Array
    counts: Mapping = field(default_factory=dict)


@pytree_dataclass
class VisBuffer(_Ids):
    """Per-pixel visibility: which triangle is nearest at each pixel (or sample) centre.

    tri_id:   int32[H, W]    triangle index into the face array, -1 where nothing is covered.
                             Row 0 is the top of the image.
    depth:    float32[H, W]  window depth in [0, 1] (GL: z_ndc * 0.5 + 0.5), interpolated
                             linearly in screen space; 1.0 where empty.
    bary:     float32[H, W, 3] perspective-correct barycentrics of the pixel centre with respect
                             to the triangle's three vertices (face order); 0 where empty.
    dbary_dx: float32[H, W, 3] analytic derivative of ``bary`` with respect to window x
                             (one pixel to the right); 0 where empty.
    dbary_dy: float32[H, W, 3] the same with respect to window y (one pixel down the image).
    counts:   mapping (dict or ``Counts``) of int32 scalars read off the raster work lists
              (``fragments``: covered (pixel, triangle) pairs; ``work_items``: pixel tests
              run; ``clipped``: triangles that crossed a clip plane; ``dropped_nonfinite``:
              triangles dropped for a NaN or infinite vertex).
    motion:   float32[H, W, 2] or None: on request (``pipelines.visibility`` with a previous
              frame), the window offset to where each pixel's surface point was in the
              previous frame (``raster.motion``; x right, y down, 0 where empty).
    prev_depth: float32[H, W] or None: that point's window depth in the previous frame.
    """

    tri_id: Array
    depth: Array
    bary: Array
    dbary_dx: Array
    dbary_dy: Array
    counts: Mapping = field(default_factory=dict)
    motion: Array | None = None
    prev_depth: Array | None = None


@pytree_dataclass
class SurfacePoints:
    """A batch of N surface points to shade; the one input of ``shading.shade``.

    position:       float32[N, 3] world position.
    normal:         float32[N, 3] unit geometric (face) normal, oriented towards the viewer.
    shading_normal: float32[N, 3] unit interpolated vertex normal, oriented towards the viewer
                    (the normal map, if any, is applied inside ``shade``).
    tangent:        float32[N, 4] interpolated tangent (xyz) and bitangent sign (w).
    uv:             float32[N, 2] texture coordinates.
    duv_dx:         float32[N, 2] d uv / d window x (per pixel of the image being shaded).
    duv_dy:         float32[N, 2] d uv / d window y.
    view:           float32[N, 3] unit vector from the point towards the eye.
    material:       int32[N] material index.
    tri_id:         int32[N] triangle index (-1 for points that are not valid).
    valid:          bool[N] False for padding lanes of a chunk; their colour is ignored.
    """

    position: Array
    normal: Array
    shading_normal: Array
    tangent: Array
    uv: Array
    duv_dx: Array
    duv_dy: Array
    view: Array
    material: Array
    tri_id: Array
    valid: Array


@pytree_dataclass
class Frame:
    """What every pipeline returns.

    image:  float32[H, W, 3] linear RGB.
    counts: dict[str, int32/float32 scalar], read off the work lists that drove the
            computation (``shade_invocations``, ``helper_lanes``, ``covered_pixels``,
            ``overshading``, ``waves``, ``lane_utilization``, ``bytes_intermediate``, ...).
    aux:    dict[str, Array] of per-pixel extras a figure may want (decision maps, ids, ...).
    """

    image: Array
    counts: dict = field(default_factory=dict)
    aux: dict = field(default_factory=dict)
