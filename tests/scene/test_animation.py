"""Scene animation: poses against a NumPy oracle, the static case, and TOML declarations with
errors that name the file and the key."""

import numpy as np
import pytest

from jaxrender.scene import MeshPart, SceneConfigError, build_scene, load_scene
from jaxrender.scene.animation import ObjectMotion, pose, positions_at
from jaxrender.scene.camera import look_at
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import box, grid_plane

TOL = 1e-5  # float32 pose of unit-sized objects


def _rodrigues(axis, angle):
    k = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx


def _scene(*parts, fps=60.0):
    return build_scene(list(parts), [Material()], [], make_lights([((0, 1, 0), 1.0)]),
                       look_at((0, 0, 5), (0, 0, 0)), name="anim", fps=fps)


def test_rigid_spin_orbit_and_translation_match_numpy():
    cube = box((1.0, 0.5, 0.25))
    cube.positions = cube.positions + np.array([2.0, 0.0, 0.0])
    m = ObjectMotion(spin_axis=(0, 0, 1), spin_deg_per_s=30.0, pivot=(2.0, 0.0, 0.0),
                     orbit_center=(0, 0, 0), orbit_axis=(0, 1, 0), orbit_deg_per_s=-45.0,
                     velocity=(0.1, 0.2, 0.0))
    cube.motion = m
    scene = _scene(grid_plane((1, 1)), cube, fps=30.0)
    t = 7
    s = t / 30.0
    rest = np.asarray(scene.positions, np.float64)
    got = np.asarray(pose(scene, t).positions, np.float64)
    n_plane = 4
    np.testing.assert_allclose(got[:n_plane], rest[:n_plane], atol=TOL,
                               err_msg="the still plane moved")
    pivot = np.array([2.0, 0.0, 0.0])
    spun = (rest[n_plane:] - pivot) @ _rodrigues((0, 0, 1), np.deg2rad(30.0) * s).T
    moved_pivot = _rodrigues((0, 1, 0), np.deg2rad(-45.0) * s) @ pivot + np.array([0.1, 0.2, 0]) * s
    np.testing.assert_allclose(got[n_plane:], spun + moved_pivot, atol=TOL,
                               err_msg="rigid pose differs from spin + orbit + translation")
    nrm = np.asarray(pose(scene, t).normals, np.float64)[n_plane:]
    want = np.asarray(scene.normals, np.float64)[n_plane:] @ _rodrigues(
        (0, 0, 1), np.deg2rad(30.0) * s).T
    np.testing.assert_allclose(nrm, want, atol=TOL, err_msg="normals not rotated with the object")


def test_sway_grows_with_height_and_leaves_the_base():
    card = grid_plane((1.0, 1.0), (1, 4)).transformed(
        np.array([[1, 0, 0, 0], [0, 0, -1, 0.5], [0, 1, 0, 0], [0, 0, 0, 1.0]]))  # upright
    card.motion = ObjectMotion(sway_amplitude=0.2, sway_height=1.0, sway_base=0.0,
                               sway_direction=(1, 0, 0), sway_frequency_hz=2.0,
                               sway_wavelength=3.0, sway_exponent=2.0)
    scene = _scene(card)
    rest = np.asarray(scene.positions, np.float64)
    t = 11
    got = np.asarray(positions_at(scene, t), np.float64)
    phase = 2 * np.pi * rest[:, 0] / 3.0
    dx = 0.2 * rest[:, 1] ** 2 * np.sin(2 * np.pi * 2.0 * t / 60.0 + phase)
    np.testing.assert_allclose(got - rest, np.stack([dx, 0 * dx, 0 * dx], 1), atol=TOL,
                               err_msg="sway displacement differs from amplitude * h^2 * sin")
    assert np.all(np.abs(got - rest)[rest[:, 1] == 0.0] == 0.0), "the base must not move"


def test_a_static_scene_compiles_no_animation():
    scene = load_scene("spheres", rows=1, cols=1)
    assert scene.animation is None and not scene.effects.motion
    assert pose(scene, 9) is scene
    spin = load_scene("spheres_spin", rows=1, cols=1)
    assert spin.effects.motion and spin.animation.rigid and not spin.animation.sways
    wind = load_scene("foliage_wind", n_cards=4)
    assert wind.animation.sways and not wind.animation.rigid
    with pytest.raises(ValueError, match="effects.motion"):
        build_scene([grid_plane((1, 1))], [Material()], [], make_lights([((0, 1, 0), 1.0)]),
                    look_at((0, 0, 5), (0, 0, 0)), name="x", effects={"motion": True})


SCENE = """
[camera]
eye = [0, 1, 3]
target = [0, 0, 0]
[[meshes]]
primitive = "box"
size = 1
{extra}
"""


def _load(tmp_path, extra):
    p = tmp_path / "moving.toml"
    p.write_text(SCENE.format(extra=extra))
    return load_scene(p), p


def test_toml_declares_motion(tmp_path):
    scene, _ = _load(tmp_path, "motion = { spin_axis = [0, 1, 0], spin_deg_per_s = 90 }")
    assert scene.effects.motion and scene.animation.rigid
    quarter = np.asarray(positions_at(scene, 60), np.float64)
    rest = np.asarray(scene.positions, np.float64)
    np.testing.assert_allclose(quarter, rest @ _rodrigues((0, 1, 0), np.pi / 2).T, atol=1e-5,
                               err_msg="90 deg/s for 60 frames at 60 Hz is a quarter turn")


@pytest.mark.parametrize("extra, key, problem", [
    ("motion = { spin_deg_per_second = 90 }", "meshes[0].motion.spin_deg_per_second",
     "unknown key"),
    ("motion = { spin_deg_per_s = 'fast' }", "meshes[0].motion.spin_deg_per_s", "a number"),
    ("motion = { spin_axis = [0, 0, 0], spin_deg_per_s = 9 }", "meshes[0].motion.spin_axis",
     "non-zero"),
    ("motion = { sway_height = 2.0, spin_deg_per_s = 9 }", "meshes[0].motion.sway_height",
     "sway_amplitude"),
    ("motion = { spin_axis = [1, 0, 0] }", "meshes[0].motion.spin_axis", "spin_deg_per_s"),
    ("motion = { velocity = [0, 0, 0] }", "meshes[0].motion", "declares no motion"),
])
def test_toml_motion_errors_name_file_and_key(tmp_path, extra, key, problem):
    with pytest.raises(SceneConfigError, match=problem) as e:
        _load(tmp_path, extra)
    assert e.value.key == key and e.value.path.endswith("moving.toml"), str(e.value)


def test_toml_fps_needs_a_motion(tmp_path):
    p = tmp_path / "still.toml"
    p.write_text("fps = 30\n" + SCENE.format(extra=""))
    with pytest.raises(SceneConfigError, match="no mesh has a motion") as e:
        load_scene(p)
    assert e.value.key == "fps"
    p.write_text("fps = 0\n" + SCENE.format(extra="motion = { velocity = [1, 0, 0] }"))
    with pytest.raises(SceneConfigError, match="> 0") as e:
        load_scene(p)
    assert e.value.key == "fps"


def test_mesh_part_motion_survives_transforms():
    part = MeshPart(np.zeros((3, 3)), np.array([[0, 1, 2]]), motion=ObjectMotion(velocity=(1, 0, 0)))
    assert part.transformed(np.eye(4)).motion == part.motion


def _posed_frames_oracle(motions, positions, normals, tangents, vertex_object, t, eps=1e-3):
    """Normals cof(J) n = det(J) J^-T n (what a deformed triangle's e1 x e2 becomes: the normal
    keeps the side its winding gives, even where the sway folds the surface) and tangents J t,
    normalized, with J the central-difference Jacobian of each vertex's posed position over
    its rest position (float64, from pose_arrays itself)."""
    from jaxrender.scene.animation import build_animation, pose_arrays

    def posed(p):
        anim = build_animation(motions, p, normals, tangents, vertex_object)
        return np.asarray(pose_arrays(anim, t)[0], np.float64)

    cols = [(posed(positions + eps * e) - posed(positions - eps * e)) / (2 * eps)
            for e in np.eye(3)]
    jac = np.stack(cols, axis=-1)  # [V, 3, 3], d x / d p
    n = np.linalg.det(jac)[:, None] * np.einsum("vji,vj->vi", np.linalg.inv(jac), normals)
    tg = np.einsum("vij,vj->vi", jac, tangents[:, :3])
    unit = lambda v: v / np.linalg.norm(v, axis=-1, keepdims=True)  # noqa: E731
    return unit(n), unit(tg)


@pytest.mark.parametrize("rigid", [False, True], ids=["sway", "sway+spin"])
def test_swayed_normals_and_tangents_follow_the_bent_surface(rigid):
    from jaxrender.scene.animation import build_animation, pose_arrays

    rng = np.random.default_rng(7 + rigid)
    v = 64
    pos = rng.uniform([-1.0, 0.1, -1.0], [1.0, 1.5, 1.0], (v, 3))
    nrm = rng.normal(size=(v, 3))
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    tan = np.cross(nrm, rng.normal(size=(v, 3)))
    tan = np.concatenate([tan / np.linalg.norm(tan, axis=-1, keepdims=True),
                          np.ones((v, 1))], axis=-1)
    obj = (np.arange(v) % 2).astype(np.int32)
    motions = [ObjectMotion(sway_amplitude=0.3, sway_direction=(1.0, 0.0, 0.5),
                            sway_frequency_hz=1.3, sway_wavelength=2.0, sway_height=1.2,
                            sway_exponent=2.0, sway_base=0.0,
                            spin_deg_per_s=40.0 if rigid else 0.0, spin_axis=(0, 1, 1),
                            pivot=(0.0, 0.0, 0.0)),
               ObjectMotion(sway_amplitude=0.15, sway_direction=(0.0, 0.0, 1.0),
                            sway_exponent=1.5, sway_base=0.0, pivot=(0.0, 0.0, 0.0))]
    t = 13
    anim = build_animation(motions, pos, nrm, tan, obj)
    _, got_n, got_t = (np.asarray(a, np.float64) for a in pose_arrays(anim, t))
    want_n, want_t = _posed_frames_oracle(motions, pos, nrm, tan, obj, t)
    assert not np.allclose(want_n, nrm, atol=1e-2), "the sway does not bend these normals"
    np.testing.assert_allclose(got_n, want_n, atol=2e-3,
                               err_msg="swayed normals are not cof(J) n of the posed surface")
    np.testing.assert_allclose(got_t[:, :3], want_t, atol=2e-3,
                               err_msg="swayed tangents are not J t of the posed surface")
    np.testing.assert_array_equal(got_t[:, 3], tan[:, 3], err_msg="tangent sign changed")


def test_bounds_hold_every_pose_of_a_spinning_orbiting_swaying_scene():
    # The shadow map's light box is the scene's bounds: every pose must lie inside them.
    from jaxrender.scene.animation import pose_arrays

    cube = box((1.0, 0.5, 0.25))
    cube.positions = cube.positions + np.array([2.0, 0.0, 0.0])
    cube.motion = ObjectMotion(spin_axis=(0, 0, 1), spin_deg_per_s=50.0, orbit_center=(0, 0, 0),
                               orbit_axis=(0, 1, 0), orbit_deg_per_s=35.0)
    card = grid_plane((1.0, 1.0), (1, 4)).transformed(
        np.array([[1, 0, 0, -2.0], [0, 0, -1, 0.5], [0, 1, 0, 0], [0, 0, 0, 1.0]]))
    card.motion = ObjectMotion(sway_amplitude=0.4, sway_height=1.0, sway_base=0.0)
    still = grid_plane((1, 1))
    scene = _scene(still, cube, card, fps=10.0)
    lo, hi = (np.asarray(b, np.float64) for b in scene.bounds)
    rest = np.asarray(scene.positions, np.float64)
    posed = np.concatenate([np.asarray(pose_arrays(scene.animation, t)[0], np.float64)
                            for t in range(0, 200, 3)])
    assert np.all(posed >= lo - 1e-5) and np.all(posed <= hi + 1e-5), (
        f"a pose leaves the bounds {lo} .. {hi}: {posed.min(0)} .. {posed.max(0)}")
    assert np.any(posed.min(0) < rest.min(0) - 0.1), "the motion never leaves the rest box"
    np.testing.assert_array_equal(np.asarray(_scene(still).bounds),
                                  np.stack([rest[:4].min(0), rest[:4].max(0)]).astype(np.float32),
                                  err_msg="a still scene's bounds are not its rest box")
