"""surface_points against NumPy, the LOD of a tilted plane against its analytic derivative, every
built-in scene through the shared rasterizer, and the shadow map."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from shading_helpers import RES, PAD_T, PAD_V, flat, padding_part, raster

from jaxrender.scene import Material, build_scene, list_builtin_scenes, load_scene, look_at, make_lights
from jaxrender.scene.mesh import box, grid_plane, trs_matrix
from jaxrender.shading import load_lit_scene, shade, surface_points, with_shadow_map
from jaxrender.shading.texture import lod_isotropic

_TOL = 1e-5


def test_surface_points_interpolate_and_orient():
    rng = np.random.default_rng(0)
    scene = load_scene("sliver")
    cam = look_at((0.3, 0.2, -4.0), (0, 0, 0))  # from behind the wall: normals must flip
    n = 16
    tri = rng.integers(0, 64, n).astype(np.int32)  # the fan (non-degenerate)
    b = rng.dirichlet([1, 1, 1], n).astype(np.float32)
    db = rng.normal(size=(n, 3)).astype(np.float32) * 1e-2
    tri[3] = -1
    p = surface_points(scene, cam, jnp.asarray(tri), jnp.asarray(b), jnp.asarray(db), jnp.asarray(-db))
    f = np.asarray(scene.faces)[np.maximum(tri, 0)]
    pos = np.einsum("nk,nkc->nc", b, np.asarray(scene.positions)[f])
    uv = np.asarray(scene.uvs)[f]
    ok = tri >= 0
    np.testing.assert_allclose(np.asarray(p.position)[ok], pos[ok], atol=_TOL, err_msg="position")
    np.testing.assert_allclose(np.asarray(p.uv)[ok], np.einsum("nk,nkc->nc", b, uv)[ok], atol=_TOL,
                               err_msg="uv")
    np.testing.assert_allclose(np.asarray(p.duv_dx)[ok], np.einsum("nk,nkc->nc", db, uv)[ok],
                               atol=_TOL, err_msg="duv/dx by the chain rule")
    np.testing.assert_array_equal(np.asarray(p.valid), ok, err_msg="valid")
    nrm = np.asarray(p.normal)
    assert np.all(np.sum(nrm[ok] * np.asarray(p.view)[ok], axis=1) > 0), "normal towards viewer"
    np.testing.assert_allclose(nrm[ok], np.tile([0, 0, -1.0], (ok.sum(), 1)), atol=_TOL,
                               err_msg="flipped geometric normal")
    for leaf in jax.tree_util.tree_leaves(p):
        assert np.all(np.isfinite(np.asarray(leaf, np.float64))), "invalid points must be finite"


def test_lod_on_tilted_plane_matches_analytic_derivative():
    # A plane y = 0 with uv = (x, -z) / size + 0.5, seen from height h looking down at pitch.
    size = 8.0
    plane = grid_plane((size, size))
    eye, target = np.array([0.0, 1.0, 3.0]), np.array([0.0, 0.0, 0.0])
    cam = look_at(eye, target, fov_y_deg=60)
    scene = build_scene([plane], [Material()], [], make_lights(), cam, name="tilted")
    vis = raster(scene.positions, scene.faces, cam)
    p = surface_points(scene, cam, *flat(vis))
    valid = np.asarray(p.valid)
    rot = np.asarray(cam.rotation, np.float64)
    f_px = RES / (2 * np.tan(np.deg2rad(30)))

    def uv_at(px, py):  # ray through window point (px, py) hits y = 0
        d = rot.T @ np.array([(px - RES / 2) / f_px, -(py - RES / 2) / f_px, -1.0])
        hit = eye + d * (-eye[1] / d[1])
        return np.array([hit[0] / size + 0.5, -hit[2] / size + 0.5])

    ys, xs = np.nonzero(valid.reshape(RES, RES))
    eps = 1e-3
    for y, x in list(zip(ys, xs))[:: max(len(ys) // 40, 1)]:
        cx, cy = x + 0.5, y + 0.5
        ddx = (uv_at(cx + eps, cy) - uv_at(cx - eps, cy)) / (2 * eps)
        ddy = (uv_at(cx, cy + eps) - uv_at(cx, cy - eps)) / (2 * eps)
        i = y * RES + x
        np.testing.assert_allclose(np.asarray(p.uv)[i], uv_at(cx, cy), atol=1e-4, err_msg="uv")
        np.testing.assert_allclose(np.asarray(p.duv_dx)[i], ddx, rtol=1e-3, atol=1e-6,
                                   err_msg=f"duv/dx at pixel {(x, y)}")
        np.testing.assert_allclose(np.asarray(p.duv_dy)[i], ddy, rtol=1e-3, atol=1e-6,
                                   err_msg=f"duv/dy at pixel {(x, y)}")
        lod = float(lod_isotropic(p.duv_dx[i:i + 1], p.duv_dy[i:i + 1], 256)[0])
        want = np.log2(256 * max(np.linalg.norm(ddx), np.linalg.norm(ddy)))
        np.testing.assert_allclose(lod, want, atol=2e-3, err_msg=f"LOD at pixel {(x, y)}")


_SMALL = {"many_small": dict(n_triangles=4000), "terrain": dict(res=32),
          "spheres": dict(rows=2, cols=3), "foliage": dict(n_cards=60),
          "grass": dict(n_blades=500)}


def test_every_builtin_renders_without_nan():
    for name, _ in list_builtin_scenes():
        scene = load_scene(name, **_SMALL.get(name, {}))
        scene = dataclasses.replace(scene, effects=scene.effects.replace(shadows=False))
        vis = raster(scene.positions, scene.faces, scene.camera)
        img = np.asarray(shade(surface_points(scene, scene.camera, *flat(vis)), scene))
        assert np.all(np.isfinite(img)), f"{name}: non-finite pixels"
        covered = np.asarray(vis.tri_id) >= 0
        assert covered.mean() > 0.05, f"{name}: the default camera sees almost nothing"
        assert img.reshape(-1, 3)[covered.reshape(-1)].max() > 1e-3, f"{name}: all black"


def test_load_scene_is_pure_and_load_lit_scene_renders_the_shadow_map():
    small = {"shadow_map_size": RES}
    assert load_scene("room", effects=small).shadow is None
    lit = load_lit_scene("room", effects=small)
    assert lit.effects.shadows and lit.shadow.depth.shape == (RES, RES)
    assert load_lit_scene("room", effects=dict(small, shadows=False)).shadow is None


def test_shadow_map_darkens_the_floor_under_a_box():
    floor = grid_plane((6, 6))
    blocker = box((1.0, 0.2, 1.0)).transformed(trs_matrix((0, 1.5, 0)))
    parts = [floor, blocker]
    v = sum(len(q.positions) for q in parts)
    t = sum(len(q.faces) for q in parts)
    parts.append(padding_part(PAD_V - v, PAD_T - t))  # one raster compile for all tests
    cam = look_at((0, 4, 4), (0, 0, 0))
    scene = build_scene(parts, [Material(albedo=(0.5,) * 3)], [], make_lights([((0, 1, 0), 1.0)]),
                        cam, name="shadow", shadows=True, effects={"shadow_map_size": RES})
    scene = with_shadow_map(scene)
    assert scene.shadow.depth.shape == (RES, RES)
    from jaxrender.shading.shadow import shadow_factor

    pos = jnp.asarray([[0.0, 0.0, 0.0], [2.5, 0.0, 2.5], [0.0, 1.61, 0.0]], jnp.float32)
    nrm = jnp.asarray([[0.0, 1.0, 0.0]] * 3, jnp.float32)
    got = np.asarray(shadow_factor(scene.shadow, pos, nrm, scene.effects.shadow_bias))[:, 0]
    np.testing.assert_allclose(got, [0.0, 1.0, 1.0], atol=1e-6,
                               err_msg="under the box / open floor / top of the box")
