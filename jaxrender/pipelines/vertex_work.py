"""Vertex work: how many vertices each pipeline fetches and transforms, and their bytes.

A raster pass runs the vertex shader once per vertex of the scene (the scene's vertex array is
what ``visibility.clip_vertices`` transforms; post-transform reuse is assumed perfect, so a
vertex shared by several triangles counts once). A depth-only pass (forward's Z pre-pass, the
visibility buffer's id pass) fetches positions only; a pass that interpolates attributes
fetches the whole vertex. Forward with a Z pre-pass transforms every vertex twice. The
visibility buffer's shading fetches and transforms the three vertices of the triangle again
for each shaded pixel (``vertex_fetch = "pixel"``) or, with Decima's vertex wave commands,
once per distinct triangle of each wave (``"wave"``), read off the sorted work list.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.quads import BIG, first_of_segment_index, segment_starts
from jaxrender.sorting import lex_sort
from jaxrender.types import Array

POSITION_BYTES = 12  # float32 x 3: all a depth-only pass reads
VERTEX_BYTES = 32  # position and normal (float32 x 3 each) and uv (float32 x 2)
VERTEX_FETCHES = ("wave", "pixel")


def vertex_counts(scene, *, full_passes: int, position_passes: int = 0,
                  shaded_vertices: Array | int = 0) -> dict:
    """{vertex_invocations, vertex_bytes} of ``full_passes`` raster passes that fetch whole
    vertices, ``position_passes`` depth-only ones, and ``shaded_vertices`` whole vertices
    fetched again by a shading pass."""
    n_vertices = int(scene.positions.shape[0])
    shaded = jnp.asarray(shaded_vertices, jnp.int32)
    invocations = n_vertices * (int(full_passes) + int(position_passes)) + shaded
    nbytes = (n_vertices * (int(full_passes) * VERTEX_BYTES + int(position_passes)
                            * POSITION_BYTES) + shaded * VERTEX_BYTES)
    return {"vertex_invocations": invocations, "vertex_bytes": nbytes}


def wave_triangles(run_starts: Array, live_sorted: Array, tri_sorted: Array, wave_size: int,
                   n_tris: int) -> Array:
    """int32: distinct (wave, triangle) pairs of a sorted work list whose wave runs start at
    ``run_starts`` (each run fills waves of ``wave_size`` in order); ``tri_sorted`` is each
    item's triangle."""
    n = run_starts.shape[0]
    idx = jnp.arange(n, dtype=jnp.int32)
    rank = idx - first_of_segment_index(run_starts)
    wave = jnp.cumsum(live_sorted & (rank % int(wave_size) == 0), dtype=jnp.int32) - 1
    big = lambda a: jnp.where(live_sorted, a, BIG)  # noqa: E731
    (w_s, t_s), _ = lex_sort((big(wave), big(tri_sorted)), (n - 1, max(n_tris - 1, 0)))
    return jnp.sum(segment_starts(w_s, t_s) & (w_s != BIG), dtype=jnp.int32)
