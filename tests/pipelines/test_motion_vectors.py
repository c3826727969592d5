"""Motion vectors (previous HPOS through the same triangle's barycentrics) against the analytic
motion of each pixel's surface point: ray-plane intersection and projection in float64 NumPy;
zero for a still scene and camera; disoccluded pixels flagged."""

import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.base import PipelineConfig
from jaxrender.pipelines.visibility import Previous, visibility
from jaxrender.raster.motion import disoccluded, previous_position
from jaxrender.scene import build_scene
from jaxrender.scene.animation import ObjectMotion, pose, positions_at
from jaxrender.scene.camera import look_at
from jaxrender.scene.camera_path import frame as camera_at
from jaxrender.scene.camera_path import pan
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import grid_plane, trs_matrix

W, H = 32, 24
FPS = 60.0
MV_TOL = 1e-3  # pixels
CFG = PipelineConfig(width=W, height=H)
CAMERA = look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_y_deg=50.0)


def _quad(motion=None, z=0.0, size=2.0):
    q = grid_plane((size, size), (2, 2)).transformed(trs_matrix((0, 0, z), (90, 0, 0)))
    q.motion = motion
    return q


def _scene(*parts):
    return build_scene(list(parts), [Material()], [], make_lights([((0, 0, 1), 1.0)]), CAMERA,
                       name="mv", fps=FPS)


def _np_cam(cam):
    return (np.asarray(cam.eye, np.float64), np.asarray(cam.rotation, np.float64),
            float(cam.fov_y))


def _rays(cam):
    eye, rot, fov = _np_cam(cam)
    f = 1.0 / np.tan(fov / 2)
    x = (np.arange(W) + 0.5) / W * 2 - 1
    y = 1 - (np.arange(H) + 0.5) / H * 2
    xx, yy = np.meshgrid(x, y)
    d = np.stack([xx * (W / H) / f, yy / f, -np.ones_like(xx)], -1) @ rot
    return eye, d


def _project(p, cam):
    eye, rot, fov = _np_cam(cam)
    f = 1.0 / np.tan(fov / 2)
    v = (p - eye) @ rot.T
    w = -v[..., 2]
    return np.stack([(f / (W / H) * v[..., 0] / w + 1) * W / 2,
                     (1 - f * v[..., 1] / w) * H / 2], -1)


def _hit_plane(cam, point, normal):
    eye, d = _rays(cam)
    s = np.sum((point - eye) * normal) / np.sum(d * normal, -1)
    return eye + s[..., None] * d


def _centres():
    return np.stack(np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5), -1)


def _vis(scene, t, cam, prev_cam):
    """Frame t's visibility with its motion, as a pipeline's step sees it."""
    return visibility(pose(scene, t), cam, CFG,
                      previous=Previous(positions_at(scene, t - 1), prev_cam))


def _check(vis, want, what):
    covered = np.asarray(vis.tri_id) >= 0
    assert covered.sum() > 100, f"{what}: the quad must cover the view"
    got = np.asarray(vis.motion, np.float64)[covered]
    np.testing.assert_allclose(got, want[covered], atol=MV_TOL, rtol=0,
                               err_msg=f"{what}: motion vectors differ from the analytic motion")
    assert np.all(np.asarray(vis.motion)[~covered] == 0.0), f"{what}: empty pixels must be 0"


def _rot(axis, angle):
    k = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx


def test_rigid_translation():
    v = np.array([12.0, 6.0, 0.0])  # about 1.3 px per frame
    scene = _scene(_quad(ObjectMotion(velocity=tuple(v))))
    vis = _vis(scene, 1, CAMERA, CAMERA)
    p = _hit_plane(CAMERA, np.zeros(3), np.array([0.0, 0.0, 1.0]))
    _check(vis, _project(p - v / FPS, CAMERA) - _centres(), "translation")
    assert np.abs(np.asarray(vis.motion)).max() > 1.0


def test_rigid_rotation_out_of_plane():
    axis, rate = (0.3, 1.0, 0.0), np.deg2rad(200.0)
    scene = _scene(_quad(ObjectMotion(spin_axis=axis, spin_deg_per_s=200.0, pivot=(0, 0, 0))))
    t = 10
    normal = _rot(axis, rate * t / FPS) @ np.array([0.0, 0.0, 1.0])
    p = _hit_plane(CAMERA, np.zeros(3), normal)
    p_prev = p @ _rot(axis, -rate / FPS).T
    vis = _vis(scene, t, CAMERA, CAMERA)
    _check(vis, _project(p_prev, CAMERA) - _centres(), "rotation")
    assert np.abs(np.asarray(vis.motion)).max() > 0.1


def test_camera_rotation():
    scene = _scene(_quad(size=6.0))
    path = pan(CAMERA, 2, 2.5, H)
    cam, prev = camera_at(path.cameras, 1), camera_at(path.cameras, 0)
    vis = visibility(scene, cam, CFG, previous=Previous(scene.positions, prev))
    p = _hit_plane(cam, np.zeros(3), np.array([0.0, 0.0, 1.0]))
    _check(vis, _project(p, prev) - _centres(), "camera rotation")
    assert np.abs(np.asarray(vis.motion)[..., 0]).min() > 2.0


def test_still_scene_and_camera_have_zero_motion():
    scene = _scene(_quad(), _quad(z=-1.0, size=8.0))
    vis = visibility(scene, CAMERA, CFG, previous=Previous(scene.positions, CAMERA))
    assert np.all(np.asarray(vis.motion) == 0.0), "a still frame must have no motion"
    np.testing.assert_allclose(np.asarray(vis.prev_depth), np.asarray(vis.depth), atol=1e-5,
                               err_msg="previous depth of a still frame is its depth")
    assert visibility(scene, CAMERA, CFG).motion is None, "motion computed unasked"


def _erode(mask, n=1):
    for _ in range(n):
        p = np.pad(mask, 1, constant_values=False)
        mask = mask & p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]
    return mask


def test_disoccluded_pixels_are_flagged():
    px_per_frame = 6.0
    speed = px_per_frame * 2 * 4.0 * np.tan(np.deg2rad(25.0)) / H * FPS  # world units per s
    front = _quad(ObjectMotion(velocity=(speed, 0.0, 0.0)), size=1.5)
    scene = _scene(front, _quad(z=-1.0, size=8.0))
    objects = lambda v: np.where(np.asarray(v.tri_id) >= 0,  # noqa: E731
                                 np.asarray(scene.tri_object)[np.maximum(v.tri_id, 0)], -1)
    before = _vis(scene, 0, CAMERA, CAMERA)
    now = _vis(scene, 1, CAMERA, CAMERA)
    obj_b, obj_n = objects(before), objects(now)
    lost = np.asarray(disoccluded(previous_position(now.motion), now.prev_depth,
                                  jnp.asarray(obj_n), before.depth, jnp.asarray(obj_b),
                                  CAMERA, 0.01))
    uncovered = _erode(obj_b == 0, 1) & (obj_n == 1)
    assert uncovered.sum() >= 10, "the quad must uncover background"
    assert lost[uncovered].all(), "background the quad covered last frame must be flagged"
    stays = _erode(obj_b == 1, 2) & (obj_n == 1)
    assert stays.sum() > 100 and not lost[stays].any(), "background seen in both is not lost"
    moved = _erode(obj_n == 0, 1) & np.roll(_erode(obj_b == 0, 1), 6, axis=1)
    assert moved.sum() >= 4 and not lost[moved].any(), "the moving quad itself is not lost"
