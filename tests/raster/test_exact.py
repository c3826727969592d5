"""Triangle ids equal the NumPy reference rasterizer, pixel for pixel, on many random scenes."""

import numpy as np
import pytest

from jaxrender.raster import rasterize_clip, samples
from jaxrender.raster.numpy_reference import rasterize_reference
from tests.raster.conftest import N_FACES, pad

W, H = 64, 48
# Pixels where the nearest two fragments are closer than this in depth are ties that float32
# (JAX) and float64 (reference) may break differently; everything else must agree exactly.
DEPTH_TIE = 1e-5


def _random_scene(rng, kind: str):
    n = N_FACES
    if kind == "mixed_sizes":  # sub-pixel to screen-filling, past the viewport edges
        centre = rng.uniform(-1.4, 1.4, (n, 1, 2))
        size = np.exp(rng.uniform(np.log(1e-3), np.log(2.5), (n, 1, 1)))
        xy = centre + size * rng.normal(size=(n, 3, 2))
    elif kind == "pixel_centres":  # every vertex exactly on a pixel centre
        px = rng.integers(-4, W + 4, (n, 3)) + 0.5
        py = rng.integers(-4, H + 4, (n, 3)) + 0.5
        xy = np.stack([px / W * 2 - 1, 1 - py / H * 2], -1)
    elif kind == "shared_edges":  # fans around shared vertices: many exactly shared edges
        hub = rng.uniform(-1, 1, (n // 8, 1, 2))
        ring = hub + rng.uniform(0.05, 0.6) * np.stack(
            [np.cos(np.linspace(0, 2 * np.pi, 9)), np.sin(np.linspace(0, 2 * np.pi, 9))], -1
        )[None]
        a, b = ring[:, :-1], ring[:, 1:]
        xy = np.stack([np.broadcast_to(hub, a.shape), a, b], 2).reshape(-1, 3, 2)
    else:
        raise ValueError(kind)
    w = rng.uniform(0.5, 3.0, (xy.shape[0], 3, 1))
    z = rng.uniform(-0.9, 0.9, (xy.shape[0], 3, 1))
    clip = np.concatenate([xy * w, z * w, w], -1).reshape(-1, 4).astype(np.float32)
    faces = np.arange(len(clip)).reshape(-1, 3).astype(np.int32)
    return pad(clip, faces, n_verts=3 * N_FACES)


@pytest.mark.parametrize("kind", ["mixed_sizes", "pixel_centres", "shared_edges"])
@pytest.mark.parametrize("cull", [False, True])
def test_tri_id_equals_numpy_reference(rng, kind, cull):
    for _ in range(2):
        clip, faces = _random_scene(rng, kind)
        vis = rasterize_clip(clip, faces, W, H, cull_backfaces=cull)
        ref = rasterize_reference(clip, faces, W, H, cull_backfaces=cull)
        got = np.asarray(vis.tri_id)
        real = (got != ref["tri_id"]) & (ref["depth_gap"] >= DEPTH_TIE)
        np.testing.assert_array_equal(
            real, False, err_msg=f"{kind}: {real.sum()} pixels disagree with the reference"
        )
        assert int(vis.counts["fragments"]) == ref["fragments"], (kind, "fragment count")
        covered = ref["tri_id"] >= 0
        np.testing.assert_allclose(
            np.asarray(vis.depth)[covered], ref["depth"][covered], atol=1e-6,
            err_msg=f"{kind}: window depth",
        )


def test_sample_offsets_each_equal_reference(rng):
    clip, faces = _random_scene(rng, "mixed_sizes")
    pattern = samples.msaa(4)
    vis = rasterize_clip(clip, faces, W, H, sample_offsets=pattern)
    assert vis.tri_id.shape == (4, W and H, W) or vis.tri_id.shape == (4, H, W)
    total = 0
    for s, off in enumerate(pattern):
        ref = rasterize_reference(clip, faces, W, H, offset=off)
        real = (np.asarray(vis.tri_id[s]) != ref["tri_id"]) & (ref["depth_gap"] >= DEPTH_TIE)
        np.testing.assert_array_equal(real, False, err_msg=f"sample {s} at {off}")
        total += ref["fragments"]
    assert int(vis.counts["fragments"]) == total
