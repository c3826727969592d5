"""Property tests of the rasterizer's invariants on random triangles (issue 10), bounded so CI
stays fast: every example is padded to one shape, so one compile serves them all.

The fixed cases these generalise live in tests/raster/test_robust.py (a jittered grid, slivers,
near-plane crossings) and tests/raster/test_exact.py (the NumPy reference, pixel for pixel).
"""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jaxrender.raster import fragments, rasterize_clip
from jaxrender.raster.numpy_reference import rasterize_reference
from jaxrender.scene.mesh import grid_mesh

W, H = 24, 16
N_VERTS, N_FACES = 256, 128
BARY_TOL = 1e-5
SETTINGS = settings(max_examples=25, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


def _pad(clip, faces):
    v = np.zeros((N_VERTS, 4), np.float32)
    v[:, 3] = 1.0
    v[: len(clip)] = clip
    f = np.zeros((N_FACES, 3), np.int32)  # degenerate on vertex 0: never covers
    f[: len(faces)] = faces
    return v, f


def _counts(clip, faces):
    fr = fragments(clip, faces, W, H, capacity=8 * W * H)
    valid = np.asarray(fr.valid)
    pix, tri = np.asarray(fr.pixel)[valid], np.asarray(fr.tri)[valid]
    return pix, tri


def _homogeneous(xy, w):
    """NDC xy float[N, 2] and w float[N] -> clip float32[N, 4] (z = 0.1 w, inside the frustum)."""
    w = np.asarray(w, np.float64)[:, None]
    return np.concatenate([xy * w, 0.1 * w, w], 1).astype(np.float32)


seeds = st.integers(0, 2**32 - 1)


@SETTINGS
@given(seed=seeds, scale=st.sampled_from([0.02, 0.05, 0.5, 2.0]))
def test_two_triangles_sharing_an_edge_cover_their_union_exactly_once(seed, scale):
    # Edge b-c shared; a and d on opposite sides of it, so the pair is a (possibly non-convex)
    # quadrilateral without overlap. Perspective w per vertex, shared vertices shared exactly.
    rng = np.random.default_rng(seed)
    b, c = rng.uniform(-1.2, 1.2, (2, 2))
    if np.allclose(b, c):
        c = b + 0.1
    n = np.array([-(c - b)[1], (c - b)[0]])
    n /= np.linalg.norm(n)
    t = rng.uniform(-0.5, 1.5, 2)
    # a and d at least 0.01 NDC (0.12 px) off the line: snapping (1/256 px) cannot move them
    # across it, so the triangles cannot overlap.
    a = b + t[0] * (c - b) + n * rng.uniform(0.5, 1.0) * scale
    d = b + t[1] * (c - b) - n * rng.uniform(0.5, 1.0) * scale
    xy = np.stack([a, b, c, d])
    clip = _homogeneous(xy, rng.uniform(0.3, 3.0, 4))
    faces = np.array([[0, 1, 2], [2, 1, 3]], np.int32)
    clip, faces = _pad(clip, faces)
    pix, _ = _counts(clip, faces)
    count = np.bincount(pix, minlength=W * H)
    assert count.max() <= 1, "a pixel covered by both triangles"
    ref = rasterize_reference(clip, faces, W, H)["coverage_count"].reshape(-1)
    np.testing.assert_array_equal(count, ref, err_msg="union differs from the exact rule")


@SETTINGS
@given(seed=seeds, nx=st.integers(2, 9), ny=st.integers(2, 7),
       jitter=st.sampled_from([0.0, 0.1, 0.2]))
def test_a_jittered_grid_is_watertight(seed, nx, ny, jitter):
    # A shared-vertex grid overfilling the screen, interior vertices jittered (<= 0.2 cell
    # cannot fold a triangle), random w per vertex: every pixel covered exactly once.
    v2, faces = grid_mesh(nx, ny, extent=(-1.05, 1.05, -1.05, 1.05), jitter=jitter, seed=seed)
    rng = np.random.default_rng(seed)
    clip = _homogeneous(v2, rng.uniform(0.2, 5.0, len(v2)))
    clip, faces = _pad(clip, faces)
    pix, _ = _counts(clip, faces)
    count = np.bincount(pix, minlength=W * H)
    np.testing.assert_array_equal(count, 1, err_msg="pixels covered 0 or 2+ times")


@SETTINGS
@given(seed=seeds, kind=st.sampled_from(["any", "sliver", "tiny", "behind"]))
def test_barycentrics_of_covered_pixels_sum_to_one_in_the_unit_range(seed, kind):
    rng = np.random.default_rng(seed)
    n = 40
    p = rng.uniform(-1.5, 1.5, (n, 3, 2))
    if kind == "sliver":  # aspect ~1e4..1e7: third vertex just off the long edge
        p[:, 2] = p[:, 0] + rng.uniform(0, 1, (n, 1)) * (p[:, 1] - p[:, 0]) + \
            rng.uniform(-1e-6, 1e-6, (n, 2))
    elif kind == "tiny":
        p[:, 1:] = p[:, :1] + rng.uniform(-0.02, 0.02, (n, 2, 2))
    w = rng.uniform(0.05, 4.0, (n, 3))
    if kind == "behind":  # some vertices behind the eye (w < 0): clipped polygons
        w = np.where(rng.uniform(size=(n, 3)) < 0.3, -w, w)
    clip = np.concatenate([p * w[..., None], 0.1 * np.abs(w[..., None]), w[..., None]], -1)
    clip = clip.reshape(-1, 4).astype(np.float32)
    faces = np.arange(3 * n, dtype=np.int32).reshape(-1, 3)
    clip, faces = _pad(clip, faces)
    vis = rasterize_clip(clip, faces, W, H)
    cov = np.asarray(vis.tri_id) >= 0
    for f in ("bary", "dbary_dx", "dbary_dy", "depth"):
        assert np.all(np.isfinite(np.asarray(getattr(vis, f)))), f
    b = np.asarray(vis.bary)[cov]
    assert np.all(b >= 0.0) and np.all(b <= 1.0)
    np.testing.assert_allclose(b.sum(-1), 1.0, atol=BARY_TOL)
    assert np.all(np.asarray(vis.bary)[~cov] == 0.0)
