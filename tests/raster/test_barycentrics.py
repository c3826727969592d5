"""Perspective-correct barycentrics and their analytic derivatives, against geometry itself."""

import jax.numpy as jnp
import numpy as np

from jaxrender.raster import rasterize
from jaxrender.raster.resolve import barycentrics, barycentrics_from_rows, triangle_rows
from jaxrender.scene.mesh import closed_uv_sphere
from jaxrender.scene.camera import look_at, world_to_clip
from tests.raster.conftest import pad

W, H = 64, 48


def _scene(rng):
    v, f = closed_uv_sphere(10, 20, radius=1.0)
    v = v * rng.uniform(0.7, 1.3, 3).astype(np.float32)
    eye = rng.uniform(-1, 1, 3) + np.array([0, 0, 3.5])
    cam = look_at(eye, rng.uniform(-0.2, 0.2, 3), fov_y_deg=rng.uniform(35, 70), near=0.5, far=20)
    return (*pad(v, f), cam)


def test_interpolated_point_lies_on_the_pixel_ray(rng):
    # The perspective-correct interpolation of the vertices must project back onto the centre
    # of the pixel it was computed for: the defining property of perspective correctness.
    v, f, cam = _scene(rng)
    vis = rasterize(v, f, cam, W, H)
    tri = np.asarray(vis.tri_id)
    ys, xs = np.nonzero(tri >= 0)
    p = np.einsum("nk,nkc->nc", np.asarray(vis.bary)[ys, xs], v[f[tri[ys, xs]]].astype(np.float64))
    clip = np.asarray(world_to_clip(jnp.asarray(p, jnp.float32), cam, W / H), np.float64)
    px = (clip[:, 0] / clip[:, 3] + 1) * W / 2
    py = (1 - clip[:, 1] / clip[:, 3]) * H / 2
    np.testing.assert_allclose(px, xs + 0.5, atol=2e-3, err_msg="x of reprojected point")
    np.testing.assert_allclose(py, ys + 0.5, atol=2e-3, err_msg="y of reprojected point")


def test_derivatives_match_central_differences(rng):
    v, f, cam = _scene(rng)
    vis = rasterize(v, f, cam, W, H)
    clip = world_to_clip(jnp.asarray(v), cam, W / H)
    tri = vis.tri_id
    h = 1.0 / 64.0  # a sub-pixel step: same triangle, exact rational function of the offset

    def at(dx, dy):
        off = jnp.asarray([0.5 + dx, 0.5 + dy], jnp.float32)
        return np.asarray(barycentrics(tri, clip, jnp.asarray(f), W, H, off)[0], np.float64)

    # Differences of clamped barycentrics are only exact where no step leaves the triangle:
    # keep pixels whose barycentrics stay positive over the whole +-h step.
    b = np.asarray(vis.bary)
    reach = 2 * h * (np.abs(np.asarray(vis.dbary_dx)) + np.abs(np.asarray(vis.dbary_dy)))
    interior = (np.asarray(tri) >= 0) & np.all(b > reach + 1e-3, axis=-1)
    fd_x = (at(h, 0) - at(-h, 0)) / (2 * h)
    fd_y = (at(0, h) - at(0, -h)) / (2 * h)
    scale = np.abs(fd_x[interior]).max()
    np.testing.assert_allclose(
        np.asarray(vis.dbary_dx)[interior], fd_x[interior], atol=2e-3 * scale, err_msg="d/dx"
    )
    np.testing.assert_allclose(
        np.asarray(vis.dbary_dy)[interior], fd_y[interior], atol=2e-3 * scale, err_msg="d/dy"
    )
    np.testing.assert_allclose(b[np.asarray(tri) >= 0].sum(-1), 1.0, atol=1e-5)


def test_barycentrics_at_sub_pixel_points_match_the_projected_triangle(rng):
    # barycentrics_from_rows (the reference's per-sample barycentrics) against a float64 oracle
    # of another construction: the screen-space barycentrics of the projected triangle, each
    # divided by its vertex's w and renormalised, at random points inside covered pixels.
    v, f, cam = _scene(rng)
    vis = rasterize(v, f, cam, W, H)
    clip = world_to_clip(jnp.asarray(v), cam, W / H)
    tri = np.array(vis.tri_id).reshape(-1)
    tri[rng.choice(tri.size, 40, replace=False)] = -1  # uncovered points: zeros
    ys, xs = np.divmod(np.arange(tri.size), W)
    x = (xs + rng.uniform(0.0, 1.0, tri.size)).astype(np.float32)
    y = (ys + rng.uniform(0.0, 1.0, tri.size)).astype(np.float32)
    got = barycentrics_from_rows(triangle_rows(clip, jnp.asarray(f)), jnp.asarray(tri),
                                 jnp.asarray(x), jnp.asarray(y), W, H)
    bary, ddx, ddy = (np.asarray(a, np.float64) for a in got)

    c = np.asarray(clip, np.float64)[f[np.maximum(tri, 0)]]  # [N, 3, 4]
    sx = (c[..., 0] / c[..., 3] + 1.0) * W / 2
    sy = (1.0 - c[..., 1] / c[..., 3]) * H / 2

    def oracle(qx, qy):  # (screen-space, perspective-correct) barycentrics, float64
        edge = [(1, 2), (2, 0), (0, 1)]
        s = np.stack([(sx[:, j] - sx[:, i]) * (qy - sy[:, i]) - (sy[:, j] - sy[:, i])
                      * (qx - sx[:, i]) for i, j in edge], -1)
        s = s / s.sum(-1, keepdims=True)
        p = s / c[..., 3]
        return s, p / p.sum(-1, keepdims=True)

    px, py = x.astype(np.float64), y.astype(np.float64)
    screen, persp = oracle(px, py)
    inside = (tri >= 0) & np.all(screen > 1e-3, axis=-1)  # points off the triangle are clamped
    assert inside.sum() > 500, inside.sum()
    np.testing.assert_allclose(bary[inside], persp[inside], atol=2e-5,
                               err_msg="barycentrics at sub-pixel points")
    assert np.all(bary[tri < 0] == 0) and np.all(ddx[tri < 0] == 0) and np.all(ddy[tri < 0] == 0)
    # The derivatives against central differences of the oracle, a sub-pixel step each way,
    # where the step stays inside the triangle.
    h = 1.0 / 64.0
    fd_x = (oracle(px + h, py)[1] - oracle(px - h, py)[1]) / (2 * h)
    fd_y = (oracle(px, py + h)[1] - oracle(px, py - h)[1]) / (2 * h)
    deep = inside & np.all(screen > 0.05, axis=-1)
    scale = np.abs(fd_x[deep]).max()
    np.testing.assert_allclose(ddx[deep], fd_x[deep], atol=1e-3 * scale, err_msg="d/dx")
    np.testing.assert_allclose(ddy[deep], fd_y[deep], atol=1e-3 * scale, err_msg="d/dy")
