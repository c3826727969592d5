"""Vertex work in every pipeline: vertices fetched and transformed per pass, and their bytes."""

import numpy as np
import pytest
from fdv_scenes import H, W, foliage_scene

from jaxrender.pipelines import get_pipeline, list_pipelines, make_config
from jaxrender.pipelines.micro_batch import micro_batches, unpack
from jaxrender.pipelines.vertex_work import POSITION_BYTES, VERTEX_BYTES

# The pipelines the other tests of this folder compile on the same scene and size run by default
# (their programs are shared); the rest cost a compile each and run with -m slow.
SHARED = {"forward", "deferred", "visbuffer"}
BUILTIN = sorted(p.name for p in list_pipelines()
                 if p.config_cls.__module__.startswith("jaxrender.pipelines."))
# Raster passes (whole vertices, positions only) of each pipeline's default config; the
# visibility buffer's shading adds its own, checked below.
PASSES = {"forward": (1, 0), "deferred": (1, 0), "checkerboard": (1, 0), "dacs": (1, 0),
          "object_space": (1, 0), "reference": (1, 0), "tads": (1, 0), "visbuffer": (0, 1)}


def _render(name, **params):
    scene = foliage_scene()
    cfg = make_config(name, width=W, height=H, **params)
    return scene, get_pipeline(name).render(scene, scene.camera, cfg)


def test_every_pipeline_has_expected_passes():
    assert set(BUILTIN) == set(PASSES), "a pipeline without expected vertex passes here"


@pytest.mark.parametrize("name", [n if n in SHARED else pytest.param(n, marks=pytest.mark.slow)
                                  for n in BUILTIN])
def test_every_pipeline_counts_its_vertices(name):
    scene, f = _render(name, **({"vertex_fetch": "pixel"} if name == "visbuffer" else {}))
    v = scene.positions.shape[0]
    full, pos = PASSES[name]
    shaded = 3 * int(f.counts["shade_invocations"]) if name == "visbuffer" else 0
    assert int(f.counts["vertex_invocations"]) == v * (full + pos) + shaded, name
    assert int(f.counts["vertex_bytes"]) == (v * (full * VERTEX_BYTES + pos * POSITION_BYTES)
                                             + shaded * VERTEX_BYTES), name


def test_a_z_prepass_transforms_every_vertex_twice():
    scene, plain = _render("forward")
    _, pre = _render("forward", z_prepass=True)
    v = scene.positions.shape[0]
    assert int(pre.counts["vertex_invocations"]) == 2 * v == 2 * int(
        plain.counts["vertex_invocations"])
    assert int(pre.counts["vertex_bytes"]) == v * (VERTEX_BYTES + POSITION_BYTES)


def _wave_triangles_oracle(tri: np.ndarray, mat: np.ndarray, wave: int) -> int:
    """NumPy: loose order (128x128 tile, material, Morton order in the tile), waves of
    ``wave`` items per (tile, material) run, distinct triangles per wave."""
    y, x = np.nonzero(tri >= 0)
    tile = (y // 128) * 1000 + x // 128
    z = sum(((x % 128 >> b) & 1) << (2 * b) | ((y % 128 >> b) & 1) << (2 * b + 1)
            for b in range(7))
    order = np.lexsort((z, mat[y, x], tile))
    key = np.stack([tile[order], mat[y, x][order]], 1)
    total, i = 0, 0
    while i < len(order):
        j = i
        while j < len(order) and (key[j] == key[i]).all():
            j += 1
        for s in range(i, j, wave):
            total += len(np.unique(tri[y[order[s:min(s + wave, j)]], x[order[s:min(s + wave, j)]]]))
        i = j
    return total


def test_visbuffer_wave_vertex_commands_count_distinct_triangles_per_wave():
    scene, f = _render("visbuffer")  # waves of 32
    mb = micro_batches(scene.tri_object, scene.tri_material)
    tri = np.asarray(unpack(mb, f.aux["ids"], 0)[0])
    mat = np.where(tri >= 0, np.asarray(scene.tri_material)[np.maximum(tri, 0)], -1)
    pairs = _wave_triangles_oracle(tri, mat, 32)
    assert f.counts["waves"] > 0
    assert 0 < pairs < int(f.counts["shade_invocations"])
    v = scene.positions.shape[0]
    assert int(f.counts["vertex_invocations"]) == v + 3 * pairs
    assert int(f.counts["vertex_bytes"]) == v * POSITION_BYTES + 3 * pairs * VERTEX_BYTES
