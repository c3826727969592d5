"""Where fused kernels begin and end on XLA, for the per-point arithmetic of the shader and
of the barycentrics that feed it.

XLA ends a fused kernel at every reduce, and it copies an elementwise producer into each
consumer that fuses it. A shader written with reduces over size-3 axes (dot products,
interpolation over a triangle's corners) therefore runs as dozens of kernels, each storing its
[N, 3] results; written as adds, its stages fuse, but a value read by several consumers is
computed again in each, and through a chain of normalisations that costs exponentially in the
chain's depth. The shader uses both tools below: adds inside a stage, and an explicit store
between stages (the mapped normal and its texel, the textured albedo, the shader-cost layers'
shared terms). A third is in ``shading.vec``: per-point component tuples, so that no kernel
writes an [N, 3] array whose three channels each recompute the terms they share.
"""

from __future__ import annotations

import functools
import itertools
import operator

import jax.numpy as jnp
from jax import lax

from jaxrender.types import Array


def _slices(x: Array, axis: int, keepdims: bool) -> list[Array]:
    axis = axis % x.ndim
    return [lax.index_in_dim(x, i, axis, keepdims=keepdims) for i in range(x.shape[axis])]


def sum_small(x: Array, axis: int = -1, keepdims: bool = False) -> Array:
    """``jnp.sum`` over a short static axis (3 components, 3 corners, a few lights), as adds."""
    return functools.reduce(operator.add, _slices(x, axis, keepdims))


def max_small(x: Array, axes: tuple[int, ...]) -> Array:
    """``jnp.max`` over short static axes, keeping them, as maxima (exact in any order)."""
    for axis in axes:
        x = functools.reduce(jnp.maximum, _slices(x, axis, True))
    return x


def all_small(x: Array, axis: int = -1) -> Array:
    """``jnp.all`` over a short static axis, as ands."""
    return functools.reduce(operator.and_, _slices(x, axis, False))


def any_small(x: Array, axis: int = -1) -> Array:
    """``jnp.any`` over a short static axis, as ors."""
    return functools.reduce(operator.or_, _slices(x, axis, False))


def whole_rows(tree):
    """``tree`` (an array or a pytree of them) computed by kernels of its own, for a consumer
    that reads it in rows: a scatter, or a gather in another order.

    A scatter or gather that fuses its operand's computation evaluates it once per element it
    moves: for a shader's [N, C] result, C times a point, every term the channels share (the
    lights, the texture's filter) included, and a gather evaluates it at the gathered points.
    Computed on its own, the result is a fusion whose root is its channels' concatenation,
    which evaluates all the channels of a point in one thread. On a GPU
    ``lax.optimization_barrier`` keeps the computation out of the consumer's kernel (the CPU
    pipeline removes barriers before fusion, where this is a no-op)."""
    return lax.optimization_barrier(tree)


def materialize(x: Array) -> Array:
    """``x``, stored once: its consumers read it instead of each fusing its computation.

    ``lax.optimization_barrier`` cannot do this on a CPU (XLA removes it there before
    fusion). A scatter is never fused into its consumers, and a scatter onto distinct rows in
    order is a copy."""
    def scattered(x):
        rows = jnp.arange(x.shape[0], dtype=jnp.int32)
        return jnp.zeros_like(x).at[rows].set(x, unique_indices=True, indices_are_sorted=True)

    return lax.platform_dependent(x, cpu=scattered, default=lax.optimization_barrier)


def materialize_all(*arrays: Array) -> tuple[Array, ...]:
    """``materialize`` of float arrays with the same leading axis, in one store."""
    n = arrays[0].shape[0]
    flat = [a.reshape(n, -1) for a in arrays]
    joined = materialize(jnp.concatenate(flat, axis=1))
    ends = list(itertools.accumulate(f.shape[1] for f in flat))
    starts = [0] + ends[:-1]
    return tuple(joined[:, s:e].reshape(a.shape) for a, s, e in zip(arrays, starts, ends))
