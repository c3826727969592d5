import jax
import numpy as np
import pytest

from jaxrender import metrics
from jaxrender.scene.camera import look_at

TEMPORAL_TOL_F64 = 1e-12
TEMPORAL_TOL_F32 = 1e-6
POSITION_TOL = 1e-3  # pixels, float32 reprojection against the analytic shift
WARP_TOL = 1e-10

W, H = 40, 30
NEAR, FAR, FOV_Y_DEG = 0.1, 100.0, 60.0


# --- NumPy references -------------------------------------------------------------------------


def _np_temporal_error(i, r):
    d = np.abs(np.diff(i, axis=0) - np.diff(r, axis=0))
    return d.mean(), d.mean(axis=(1, 2, 3))


def _np_bilinear(img, pos):
    h, w = img.shape[:2]
    u, v = pos[..., 0] - 0.5, pos[..., 1] - 0.5
    x0, y0 = np.floor(u).astype(int), np.floor(v).astype(int)
    fx, fy = (u - x0)[..., None], (v - y0)[..., None]
    cx0, cx1 = np.clip(x0, 0, w - 1), np.clip(x0 + 1, 0, w - 1)
    cy0, cy1 = np.clip(y0, 0, h - 1), np.clip(y0 + 1, 0, h - 1)
    return ((img[cy0, cx0] * (1 - fx) + img[cy0, cx1] * fx) * (1 - fy)
            + (img[cy1, cx0] * (1 - fx) + img[cy1, cx1] * fx) * fy)


def _np_warp_error(x, pos, valid):
    per = []
    for t in range(1, x.shape[0]):
        err = ((x[t] - _np_bilinear(x[t - 1], pos[t - 1])) ** 2).mean(axis=-1)
        m = valid[t - 1]
        if m.any():
            per.append(err[m].mean())
    return np.mean(per) if per else 0.0


def _window_depth(dist):
    """GL window depth of a point ``dist`` in front of the camera."""
    a, b = (FAR + NEAR) / (NEAR - FAR), 2 * FAR * NEAR / (NEAR - FAR)
    z_ndc = (a * -dist + b) / dist
    return 0.5 * z_ndc + 0.5


def _cam(eye, target):
    return look_at(eye, target, fov_y_deg=FOV_Y_DEG, near=NEAR, far=FAR)


def _pixel_centres():
    x = np.arange(W) + 0.5
    y = np.arange(H) + 0.5
    return np.meshgrid(x, y)  # (H, W) each


# --- temporal_error -----------------------------------------------------------------------


@pytest.mark.parametrize("dtype,tol", [(np.float64, TEMPORAL_TOL_F64),
                                       (np.float32, TEMPORAL_TOL_F32)])
def test_temporal_error_matches_numpy(seeded, dtype, tol):
    i, r = seeded.pair((5, 12, 16, 3))
    ref_mean, ref_per = _np_temporal_error(i, r)
    got = metrics.temporal_error(i, r, dtype=dtype)
    assert got.shape == () and got.dtype == dtype
    np.testing.assert_allclose(float(got), ref_mean, atol=tol, err_msg=seeded.msg("mean"))
    per = metrics.temporal_error(i, r, per_frame=True, dtype=dtype)
    assert per.shape == (4,)
    np.testing.assert_allclose(np.asarray(per), ref_per, atol=tol, err_msg=seeded.msg("per"))


def test_temporal_error_is_zero_for_the_reference_flicker(seeded):
    r, _ = seeded.pair((4, 8, 8, 3))
    offset = seeded.rng.random((8, 8, 3))  # a static error does not flicker
    assert float(metrics.temporal_error(r + offset, r, dtype=np.float64)) < TEMPORAL_TOL_F64
    with pytest.raises(ValueError, match="2 frames"):
        metrics.temporal_error(r[:1], r[:1])


# --- reproject ----------------------------------------------------------------------------


@pytest.mark.parametrize("dx,dy", [(0.3, 0.0), (0.0, -0.2), (0.25, 0.15)])
def test_reproject_translation_parallel_to_plane(dx, dy):
    """Camera translated by (dx, dy) parallel to a plane at distance dist: every pixel moves by
    the same analytic shift (f / aspect * dx / dist * W / 2, -f * dy / dist * H / 2)."""
    dist = 5.0
    cam = _cam((dx, dy, 0.0), (dx, dy, -1.0))
    prev = _cam((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    depth = np.full((H, W), _window_depth(dist), np.float32)
    focal = 1.0 / np.tan(np.deg2rad(FOV_Y_DEG) / 2)
    shift_x = focal / (W / H) * dx / dist * W / 2
    shift_y = -focal * dy / dist * H / 2
    xs, ys = _pixel_centres()
    want = np.stack([xs + shift_x, ys + shift_y], axis=-1)
    got = metrics.reproject(depth, cam, prev, W, H)
    np.testing.assert_allclose(np.asarray(got.position), want, rtol=0, atol=POSITION_TOL,
                               err_msg=f"positions, shift ({shift_x}, {shift_y})")
    on_screen = ((want[..., 0] >= 0) & (want[..., 0] <= W)
                 & (want[..., 1] >= 0) & (want[..., 1] <= H))
    assert not on_screen.all(), "the test must move some pixels off screen"
    np.testing.assert_array_equal(np.asarray(got.valid), on_screen, err_msg="off-screen mask")
    np.testing.assert_allclose(np.asarray(got.depth), depth, atol=1e-6, err_msg="depth in t-1")
    # The plane itself is what t-1 saw: the depth test keeps every on-screen pixel.
    tested = metrics.reproject(depth, cam, prev, W, H, prev_depth=depth)
    np.testing.assert_array_equal(np.asarray(tested.valid), on_screen)
    got64 = metrics.reproject(depth, cam, prev, W, H, dtype=np.float64)
    assert got64.position.dtype == np.float64


def test_reproject_rotation_matches_numpy():
    """Pure yaw: positions follow from the rotation alone (depth must not matter)."""
    theta = np.deg2rad(5.0)
    cam = _cam((0.0, 0.0, 0.0), (np.sin(theta), 0.0, -np.cos(theta)))
    prev = _cam((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    depth = np.full((H, W), _window_depth(7.0), np.float32)
    got = np.asarray(metrics.reproject(depth, cam, prev, W, H).position)
    # NumPy: view ray of each pixel -> world (yaw by -theta about y) -> prev NDC.
    focal, aspect = 1.0 / np.tan(np.deg2rad(FOV_Y_DEG) / 2), W / H
    xs, ys = _pixel_centres()
    vx, vy, vz = (2 * xs / W - 1) * aspect / focal, (1 - 2 * ys / H) / focal, -np.ones_like(xs)
    wx, wz = vx * np.cos(theta) - vz * np.sin(theta), vx * np.sin(theta) + vz * np.cos(theta)
    px = (focal / aspect * wx / -wz + 1) * W / 2
    py = (1 - focal * vy / -wz) * H / 2
    np.testing.assert_allclose(got, np.stack([px, py], -1), atol=POSITION_TOL,
                               err_msg="yaw reprojection")


def test_reproject_disocclusion_and_behind_camera():
    dist = 5.0
    cam = _cam((0.3, 0.0, 0.0), (0.3, 0.0, -1.0))
    prev = _cam((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))
    depth = np.full((H, W), _window_depth(dist), np.float32)
    prev_depth = depth.copy()
    prev_depth[10:20, 15:25] = _window_depth(2.0)  # an occluder in front of the plane in t-1
    got = metrics.reproject(depth, cam, prev, W, H, prev_depth=prev_depth)
    pos, valid = np.asarray(got.position), np.asarray(got.valid)
    ix, iy = np.floor(pos[..., 0]).astype(int), np.floor(pos[..., 1]).astype(int)
    hidden = (iy >= 10) & (iy < 20) & (ix >= 15) & (ix < 25)
    on_screen = (pos[..., 0] <= W) & (pos[..., 0] >= 0)
    assert hidden.sum() > 50
    np.testing.assert_array_equal(valid, on_screen & ~hidden, err_msg="disocclusion mask")
    # A previous camera beyond the plane sees it from behind: nothing is valid.
    beyond = _cam((0.0, 0.0, -dist - 1.0), (0.0, 0.0, -dist - 2.0))
    assert not np.asarray(metrics.reproject(depth, cam, beyond, W, H).valid).any()
    with pytest.raises(ValueError, match="depth must be"):
        metrics.reproject(depth, cam, prev, W + 1, H)


def test_reproject_sequence_stacks_cameras():
    dist = 5.0
    cams = [_cam((0.1 * t, 0.0, 0.0), (0.1 * t, 0.0, -1.0)) for t in range(3)]
    stacked = jax.tree.map(lambda *xs: jax.numpy.stack(xs), *cams)
    depths = np.full((3, H, W), _window_depth(dist), np.float32)
    seq = metrics.reproject_sequence(depths, stacked)
    assert seq.position.shape == (2, H, W, 2) and seq.valid.shape == (2, H, W)
    for t in (1, 2):
        one = metrics.reproject(depths[t], cams[t], cams[t - 1], W, H, prev_depth=depths[t - 1])
        np.testing.assert_allclose(np.asarray(seq.position[t - 1]), np.asarray(one.position),
                                   atol=1e-5, err_msg=f"pair {t}")
        np.testing.assert_array_equal(np.asarray(seq.valid[t - 1]), np.asarray(one.valid))


# --- warp_error ---------------------------------------------------------------------------


def test_warp_error_matches_numpy(seeded):
    t, h, w = 4, 10, 12
    i, r = seeded.pair((t, h, w, 3))
    base = np.stack(np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5), axis=-1)
    pos = base[None] + seeded.rng.uniform(-2.0, 2.0, (t - 1, h, w, 2))
    valid = seeded.rng.random((t - 1, h, w)) < 0.7
    valid[1] = False  # a pair with nothing valid is skipped, not averaged in as 0
    got = metrics.warp_error(i, r, pos, valid, dtype=np.float64)
    e_i, e_r = _np_warp_error(i, pos, valid), _np_warp_error(r, pos, valid)
    np.testing.assert_allclose(float(got.test), e_i, rtol=WARP_TOL, err_msg=seeded.msg("test"))
    np.testing.assert_allclose(float(got.reference), e_r, rtol=WARP_TOL,
                               err_msg=seeded.msg("reference"))
    np.testing.assert_allclose(float(got.relative), e_i / e_r, rtol=WARP_TOL,
                               err_msg=seeded.msg("relative"))
    per = metrics.warp_error(i, r, pos, valid, per_frame=True)
    assert per.test.shape == (t - 1,) and float(per.test[1]) == 0.0


def test_warp_error_exact_motion(seeded):
    """A texture scrolling by 2 pixels a frame warps exactly: the reference scores 0, a copy of
    it scores relative 1, added flicker scores more than the reference."""
    t, h, w, s = 4, 8, 20, 2
    tex = seeded.rng.random((h, w + s * t, 3))
    r = np.stack([tex[:, s * k: s * k + w] for k in range(t)])  # frame k shows tex from s*k
    base = np.stack(np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5), axis=-1)
    pos = np.broadcast_to(base + np.array([s, 0.0]), (t - 1, h, w, 2))
    valid = np.broadcast_to(pos[..., 0] <= w - 0.5, (t - 1, h, w))
    same = metrics.warp_error(r, r, pos, valid, dtype=np.float64)
    assert float(same.reference) < WARP_TOL and float(same.relative) == 1.0
    noisy_r = r + 0.01 * seeded.rng.standard_normal(r.shape)
    flicker = noisy_r + 0.1 * seeded.rng.standard_normal(r.shape)
    got = metrics.warp_error(flicker, noisy_r, pos, valid, dtype=np.float64)
    assert float(got.relative) > 10.0, got
    repro = metrics.Reprojection(pos, valid, np.zeros(valid.shape))
    np.testing.assert_allclose(float(metrics.warp_error(flicker, noisy_r, repro).test),
                               float(got.test), rtol=1e-5)
    with pytest.raises(ValueError, match="motion must be"):
        metrics.warp_error(r, r, pos[:1], valid[:1])
