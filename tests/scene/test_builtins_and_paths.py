"""Built-in scenes load with sane contents; camera paths move the image as documented."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.scene import (Effects, default_camera, list_builtin_scenes, load_scene, look_at,
                             with_effects, world_to_clip)
from jaxrender.scene.builtin import many_small
from jaxrender.scene.camera_path import dolly, frame, jitter, orbit, pan

NAMES = ["stripes", "spheres", "foliage", "thin", "terrain", "sliver", "room", "many_small",
         "foliage_wind", "spheres_spin", "grass", "glass"]


def test_every_builtin_loads():
    listed = list_builtin_scenes()
    assert [n for n, _ in listed] == NAMES
    for name, desc in listed:
        assert desc and "\n" not in desc, name
        s = load_scene(name)
        t, v = s.num_triangles, s.num_vertices
        assert s.faces.shape == (t, 3) and s.faces.dtype == jnp.int32, name
        assert int(s.faces.min()) >= 0 and int(s.faces.max()) < v, name
        for a in (s.positions, s.normals, s.uvs, s.tangents, s.textures.atlas):
            assert np.all(np.isfinite(np.asarray(a))), name
        assert s.tri_material.shape == (t,) and int(s.tri_material.max()) < s.materials.count
        assert s.tri_object.shape == (t,)
        assert isinstance(default_camera(s).eye, jax.Array)
        assert hash(s.effects) is not None and s.name == name


def test_builtin_size_parameters_and_errors():
    assert load_scene("many_small", n_triangles=5000).num_triangles >= 5000
    with pytest.raises(TypeError, match="n_triangle"):
        load_scene("many_small", n_triangle=5)
    with pytest.raises(FileNotFoundError):
        load_scene("no_such_scene")


@pytest.mark.slow
def test_many_small_large_setting_reaches_a_million():
    s = many_small(n_triangles=1_048_576)
    assert s.num_triangles >= 1_000_000


def test_effects_defaults_and_overrides():
    assert load_scene("stripes").effects.procedural
    room = load_scene("room")
    e = room.effects
    assert e.textures and e.normal_map and e.specular and e.shadows and e.emissive
    assert room.shadow is None
    assert not load_scene("foliage", effects={"alpha_test": False}).effects.alpha_test
    with pytest.raises(KeyError, match="shadowz"):
        with_effects(room, shadowz=True)
    with pytest.raises(ValueError):
        Effects(aniso_taps=0)


def _pixel(point, cam, w, h):
    c = np.asarray(world_to_clip(jnp.asarray(point, jnp.float32)[None, :], cam, w / h))[0]
    return np.array([(c[0] / c[3] * 0.5 + 0.5) * w, (0.5 - c[1] / c[3] * 0.5) * h])


def test_pan_moves_the_image_by_n_pixels_per_frame():
    w, h = 160, 90
    cam = look_at((0, 0, 5), (0, 0, 0))
    path = pan(cam, 4, 3.0, h)
    for t in range(3):  # what is at the image centre in frame t is 3 px left of it in t + 1
        c = frame(path.cameras, t)
        centre = np.asarray(c.eye) + 5.0 * np.asarray(c.forward)
        np.testing.assert_allclose(_pixel(centre, c, w, h), [w / 2, h / 2], atol=1e-3)
        x = _pixel(centre, frame(path.cameras, t + 1), w, h)
        np.testing.assert_allclose(x, [w / 2 - 3.0, h / 2], atol=1e-3, err_msg=f"pan frame {t}")
    for t, (c, prev) in enumerate(path):
        np.testing.assert_array_equal(np.asarray(prev.eye), np.asarray(frame(path.cameras, max(t - 1, 0)).eye))
        np.testing.assert_array_equal(np.asarray(prev.rotation),
                                      np.asarray(frame(path.cameras, max(t - 1, 0)).rotation))


def test_jitter_shifts_by_its_subpixel_offsets_and_vmaps():
    w, h = 64, 64
    cam = look_at((0, 1, 5), (0, 1, 0))
    path = jitter(cam, 8, h)
    offs = np.asarray(path.jitter_px)
    assert np.all(np.abs(offs) < 0.5) and len(np.unique(offs[:, 0])) == 8
    pts = jnp.asarray([[0.0, 1.0, 0.0]], jnp.float32)
    clip = jax.vmap(lambda c: world_to_clip(pts, c, 1.0))(path.cameras)  # batched cameras
    assert clip.shape == (8, 1, 4)
    for t in range(8):
        np.testing.assert_allclose(_pixel((0, 1, 0), frame(path.cameras, t), w, h),
                                   [w / 2 + offs[t, 0], h / 2 + offs[t, 1]], atol=1e-3,
                                   err_msg=f"jitter frame {t}")


def test_orbit_and_dolly():
    o = orbit((0, 0, 0), 4.0, 5, 10.0, height=1.0)
    d = np.linalg.norm(np.asarray(o.cameras.eye)[:, [0, 2]], axis=1)
    np.testing.assert_allclose(d, 4.0, rtol=1e-6, err_msg="orbit radius")
    cam = look_at((0, 0, 5), (0, 0, 0))
    eyes = np.asarray(dolly(cam, 3, 0.5).cameras.eye)
    np.testing.assert_allclose(eyes[:, 2], [5.0, 4.5, 4.0], atol=1e-6, err_msg="dolly")


def test_orbit_path_places_its_centre_by_distance_or_center():
    from jaxrender.scene.camera_path import PATH_TYPES

    build = PATH_TYPES["orbit"].build
    cam = look_at((0, 0, 5), (0, 0, 0))  # looking down -z
    ahead = build(cam, 2, 8, 8, degrees_per_frame=90.0, distance=2.0)
    # a quarter turn about the point 2 ahead, (0, 0, 3), at radius 2
    np.testing.assert_allclose(np.asarray(ahead.cameras.eye)[1], [2.0, 0.0, 3.0], atol=1e-5,
                               err_msg="orbit about the point distance ahead")
    about = build(cam, 2, 8, 8, degrees_per_frame=90.0, center=(0.0, 0.0, 1.0))
    np.testing.assert_allclose(np.asarray(about.cameras.eye)[1], [4.0, 0.0, 1.0], atol=1e-5,
                               err_msg="orbit about the given center")
    with pytest.raises(ValueError, match="'distance' has no effect when 'center' is given"):
        build(cam, 2, 8, 8, degrees_per_frame=90.0, distance=2.0, center=(0.0, 0.0, 1.0))
