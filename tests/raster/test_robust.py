"""Watertightness, hard geometry, capacities, recompiles and bad input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster import fragments, rasterize, rasterize_clip
from jaxrender.raster.numpy_reference import rasterize_reference
from jaxrender.scene.mesh import closed_uv_sphere, grid_mesh
from jaxrender.scene.camera import look_at, world_to_clip
from tests.raster.conftest import gl_clip, pad

W, H = 64, 48


def _finite(vis):
    for name in ("depth", "bary", "dbary_dx", "dbary_dy"):
        a = np.asarray(getattr(vis, name))
        assert np.all(np.isfinite(a)), f"non-finite values in {name}"


def _coverage_counts(clip, faces, **kw):
    fr = fragments(clip, faces, W, H, capacity=8 * W * H, **kw)
    pix = np.asarray(fr.pixel)[np.asarray(fr.valid)]
    return np.bincount(pix, minlength=W * H).reshape(H, W)


def test_jittered_grid_covers_every_pixel_exactly_once(rng):
    # A grid that overfills the screen, vertices jittered but shared: every pixel once.
    # (Jitter of 0.2 cell cannot fold a triangle over: a vertex and the opposite diagonal
    # approach by at most 0.57 of the 0.71 cell between them.)
    v2, faces = grid_mesh(15, 11, extent=(-1.1, 1.1, -1.1, 1.1), jitter=0.2, seed=7)
    w = rng.uniform(0.5, 2.0, (len(v2), 1))
    clip = np.concatenate([v2 * w, 0.1 * w, w], 1).astype(np.float32)
    clip, faces = pad(clip, faces)
    counts = _coverage_counts(clip, faces)
    np.testing.assert_array_equal(counts, 1, err_msg="pixels covered 0 or 2+ times")


def test_closed_sphere_covers_each_pixel_twice_and_once_when_culled():
    v, f = closed_uv_sphere(10, 20, radius=1.0)
    cam = look_at((0.3, 0.2, 3.0), (0, 0, 0), fov_y_deg=50, near=0.1, far=10)
    clip = np.asarray(world_to_clip(jnp.asarray(v), cam, W / H))
    clip, f = pad(clip, f)
    both = _coverage_counts(clip, f)
    front = _coverage_counts(clip, f, cull_backfaces=True)
    inside = both > 0
    assert inside.sum() > 300
    np.testing.assert_array_equal(both[inside], 2, err_msg="front+back layers must be exact")
    np.testing.assert_array_equal(front, inside.astype(np.int64), err_msg="front faces: once")


def test_near_plane_crossing_matches_reference_and_is_finite(rng):
    # A floor running from behind the eye to far away, plus random triangles around the eye.
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 2, 300)  # z > 0 is behind the eye
    clip = gl_clip(p, aspect=W / H)
    faces = np.arange(300).reshape(-1, 3).astype(np.int32)
    clip, faces = pad(clip, faces)
    vis = rasterize_clip(clip, faces, W, H, clip_capacity=8)
    ref = rasterize_reference(clip, faces, W, H)
    assert int(vis.counts["clipped"]) > 20
    _finite(vis)
    # Clipped vertices agree with the reference up to float32 summation order, so allow a few
    # boundary pixels (1 in 1000) to differ; everything else is exact.
    real = (np.asarray(vis.tri_id) != ref["tri_id"]) & (ref["depth_gap"] >= 1e-5)
    assert real.mean() <= 1e-3, f"{real.sum()} pixels differ"
    assert abs(int(vis.counts["fragments"]) - ref["fragments"]) <= 0.001 * ref["fragments"]


def test_nothing_behind_the_eye_is_drawn():
    # A triangle entirely behind the eye, and one with all w < 0 that would project on screen.
    p = np.array([[-1, -1, 2], [1, -1, 2], [0, 1, 2], [-1, -1, 0.05], [1, -1, 0.05], [0, 1, 0.05]])
    clip, faces = pad(gl_clip(p), np.array([[0, 1, 2], [3, 4, 5]], np.int32))
    vis = rasterize_clip(clip, faces, W, H)
    assert int(np.sum(np.asarray(vis.tri_id) >= 0)) == 0


def test_half_behind_the_eye_covers_its_visible_part():
    # A wall-sized triangle from in front of the eye to behind it: the visible part is
    # clipped, not dropped and not exploded; barycentrics stay finite and in [0, 1].
    p = np.array([[-50.0, -1.0, 10.0], [50.0, -1.0, 10.0], [0.0, -1.0, -50.0]])
    clip, faces = pad(gl_clip(p, aspect=W / H), np.array([[0, 1, 2]], np.int32))
    vis = rasterize_clip(clip, faces, W, H)
    covered = np.asarray(vis.tri_id) == 0
    assert covered[H // 2 + 2:].all() and not covered[: H // 2 - 1].any(), "floor below horizon"
    _finite(vis)
    b = np.asarray(vis.bary)[covered]
    assert (b >= 0).all() and (b <= 1).all()
    np.testing.assert_allclose(b.sum(-1), 1.0, atol=1e-5)


def test_world_coordinates_far_from_origin_match_near_origin():
    v, f = closed_uv_sphere(10, 16, radius=1.0)
    offset = np.array([1e5, -1e5, 1e5], np.float32)
    cam0 = look_at((0.2, 0.1, 3.0), (0, 0, 0), fov_y_deg=50, near=0.1, far=10)
    cam1 = look_at(offset + (0.2, 0.1, 3.0), offset, fov_y_deg=50, near=0.1, far=10)
    vp, fp = pad(v, f)
    vis0 = rasterize(vp, fp, cam0, W, H)
    vp1 = vp.copy()
    vp1[: len(v)] += offset
    vis1 = rasterize(vp1, fp, cam1, W, H)
    _finite(vis1)
    same = np.mean(np.asarray(vis0.tri_id) == np.asarray(vis1.tri_id))
    # float32 positions 1e5 away carry ~0.008 units of rounding: the silhouette moves by a
    # small fraction of a pixel, so nearly every id is unchanged.
    assert same > 0.97, same


def test_slivers_and_degenerates_are_finite_and_exact():
    # Aspect 1e6 slivers, collinear and coincident vertices, zero-area after snapping.
    pts = [
        [[-1, 0.0], [1, 1e-6], [1, 0.0]],
        [[-0.9, -0.5], [0.9, -0.5 + 2e-6], [0.0, -0.5 + 1e-6]],  # collinear-ish
        [[0.1, 0.1], [0.1, 0.1], [0.3, 0.3]],  # coincident
        [[-1, -1], [0, 0], [1, 1]],  # collinear
        [[0.2, 0.2], [0.2 + 1e-7, 0.2], [0.2, 0.2 + 1e-7]],  # snaps to nothing
        [[-1.0, 0.3], [1.0, 0.3], [1.0, 0.3 + 1.5 / H]],  # long and one pixel tall
    ]
    xy = np.asarray(pts, np.float64).reshape(-1, 2)
    clip = np.concatenate([xy, np.zeros((len(xy), 1)), np.ones((len(xy), 1))], 1)
    clip, faces = pad(clip.astype(np.float32), np.arange(len(xy)).reshape(-1, 3).astype(np.int32))
    vis = rasterize_clip(clip, faces, W, H)
    ref = rasterize_reference(clip, faces, W, H)
    np.testing.assert_array_equal(np.asarray(vis.tri_id), ref["tri_id"], err_msg="slivers")
    _finite(vis)


def test_depth_ties_go_to_the_lower_triangle_index():
    # The same triangle submitted three times (coplanar, identical depth): id 1 wins everywhere.
    tri = np.array([[-0.8, -0.8, 0.2, 1], [0.8, -0.8, 0.2, 1], [0, 0.8, 0.2, 1]], np.float32)
    clip = np.concatenate([tri, tri, tri])
    faces = np.array([[3, 4, 5], [0, 1, 2], [6, 7, 8]], np.int32) + 0
    faces[0] = [0, 1, 2]  # slot 0 is a degenerate-free copy too
    clip, faces = pad(clip, faces)
    faces[0] = [9, 9, 9]  # make slot 0 degenerate so the lowest drawing id is 1
    vis = rasterize_clip(clip, faces, W, H)
    ids = np.asarray(vis.tri_id)
    assert set(np.unique(ids)) == {-1, 1}


def test_non_finite_vertices_drop_their_triangles_and_are_counted():
    v2, faces = grid_mesh(4, 4)
    clip = np.concatenate([v2, np.zeros((len(v2), 1)), np.ones((len(v2), 1))], 1)
    clip = clip.astype(np.float32)
    clip[3, 0] = np.nan
    clip[7, 3] = np.inf
    clip, faces = pad(clip, faces)
    vis = rasterize_clip(clip, faces, W, H)
    bad = np.isin(faces[:32], [3, 7]).any(1).sum()
    assert int(vis.counts["dropped_nonfinite"]) == bad
    assert not np.isin(np.asarray(vis.tri_id), np.nonzero(np.isin(faces, [3, 7]).any(1))[0]).any()
    _finite(vis)


@pytest.mark.parametrize("work_capacity,clip_capacity", [(1 << 16, 1), (4096, 3)])
def test_tiny_capacities_give_the_same_visbuffer(rng, work_capacity, clip_capacity):
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 1, 300)
    clip, faces = pad(gl_clip(p, aspect=W / H), np.arange(300).reshape(-1, 3).astype(np.int32))
    big = rasterize_clip(clip, faces, W, H)
    small = rasterize_clip(
        clip, faces, W, H, work_capacity=work_capacity, clip_capacity=clip_capacity
    )
    for name in ("tri_id", "depth", "bary", "dbary_dx", "dbary_dy"):
        np.testing.assert_array_equal(
            np.asarray(getattr(small, name)), np.asarray(getattr(big, name)), err_msg=name
        )
    assert int(small.counts["fragments"]) == int(big.counts["fragments"])


def test_fragment_overflow_is_an_error_naming_the_capacity():
    v2, faces = grid_mesh(4, 4)
    clip = np.concatenate([v2, np.zeros((len(v2), 1)), np.ones((len(v2), 1))], 1)
    clip, faces = pad(clip.astype(np.float32), faces)
    with pytest.raises(OverflowError, match="capacity=100"):
        fragments(clip, faces, W, H, capacity=100)


def test_moving_the_camera_does_not_recompile():
    from jaxrender.raster.rasterize import rasterize_program, rasterize_traced

    def compiled():
        return rasterize_traced._cache_size() + rasterize_program._cache_size()

    v, f = pad(*closed_uv_sphere(8, 12))
    jax.block_until_ready(rasterize(v, f, look_at((0, 0.2, 3.0), (0, 0, 0), fov_y_deg=40,
                                                  near=0.1, far=10), W, H))
    before = compiled()
    for k in range(3):
        cam = look_at((0.1 * k, 0.2, 3.0 + k), (0, 0, 0), fov_y_deg=40 + k, near=0.1, far=10)
        jax.block_until_ready(rasterize(v, f, cam, W, H))
    assert compiled() == before, "a camera move recompiled the rasterizer"


def test_index_check_is_remembered_per_array_not_per_shape():
    """The faces' index range is remembered per device array; another array of the same shape
    with a bad index must still be refused."""
    v, f = pad(*closed_uv_sphere(8, 12))
    clip = np.concatenate([v, np.ones((len(v), 1), np.float32)], 1)
    good = jnp.asarray(f)
    rasterize_clip(clip, good, W, H)
    bad = good.at[3, 1].set(len(v))
    for _ in range(2):
        with pytest.raises(ValueError, match=f"face index {len(v)} out of range"):
            rasterize_clip(clip, bad, W, H)
    rasterize_clip(clip, good, W, H)


@pytest.mark.parametrize(
    "kwargs,error,match",
    [
        (dict(width=0), ValueError, "width"),
        (dict(height=-3), ValueError, "height"),
        (dict(faces=np.array([[0, 1, 99]], np.int32)), ValueError, "out of range"),
        (dict(faces=np.array([[0, -1, 2]], np.int32)), ValueError, "out of range"),
        (dict(faces=np.array([[0.0, 1.0, 2.0]])), TypeError, "integers"),
        (dict(faces=np.zeros((0, 3), np.int32)), ValueError, "empty mesh"),
        (dict(clip=np.zeros((0, 4), np.float32)), ValueError, "empty mesh"),
        (dict(clip=np.zeros((3, 3), np.float32)), ValueError, "shape"),
        (dict(sample_offsets=[(1.0, 0.5)]), ValueError, "sample_offsets"),
    ],
)
def test_bad_input_gives_a_clear_error(kwargs, error, match):
    args = dict(
        clip=np.array([[0, 0, 0, 1], [1, 0, 0, 1], [0, 1, 0, 1]], np.float32),
        faces=np.array([[0, 1, 2]], np.int32),
        width=W,
        height=H,
    )
    args.update(kwargs)
    with pytest.raises(error, match=match):
        rasterize_clip(
            args.pop("clip"), args.pop("faces"), args.pop("width"), args.pop("height"), **args
        )


@pytest.mark.parametrize("clip_capacity", [None, 4])
def test_the_gpu_traversal_reads_one_condition_when_every_item_fits_one_chunk(rng,
                                                                              clip_capacity):
    """Triangles crossing the near plane are clipped before the coverage loop and their fans
    join the unclipped triangles' list: with every item in the peeled chunk, the GPU program
    tests one loop condition (each test waits for the host). Clip chunks beyond the first,
    possible only when a chunk holds fewer than all triangles, run as further loop steps:
    each step reads its condition and its branch, and covers its fans in a peeled chunk and
    a loop tested once."""
    from jaxrender.bench import round_trips
    from jaxrender.raster.rasterize import rasterize_traced
    from jaxrender.raster.setup import SUBPIXEL_BITS

    p = rng.uniform(-3, 3, (90, 3))
    p[:, 2] = rng.uniform(-6, 2, 90)  # z > 0 is behind the eye
    clip, faces = pad(gl_clip(p, aspect=W / H), np.arange(90).reshape(-1, 3).astype(np.int32))
    n_tris = faces.shape[0]
    cap = clip_capacity or n_tris

    def draw(c):
        return rasterize_traced(c, jnp.asarray(faces), width=W, height=H, cull_backfaces=False,
                                offsets=((1 << SUBPIXEL_BITS) // 2,) * 2, work_capacity=1 << 16,
                                clip_capacity=cap, traversal="gpu")

    vis = draw(jnp.asarray(clip))
    crossing = int(vis.counts["clipped"])
    assert crossing > 2 * cap or clip_capacity is None, f"only {crossing} triangles crossing"
    extra_chunks = -(-crossing // cap) - 1
    reads = round_trips.count(draw, jnp.asarray(clip)).per_frame()[None]
    assert reads == 1 + 3 * extra_chunks, (reads, crossing, cap)
