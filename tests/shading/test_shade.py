"""Analytic answers of shade(): Lambert, point-light falloff, Blinn-Phong extremes, GGX,
stripes, alpha test, invalid points."""

import jax.numpy as jnp
import numpy as np
from shading_helpers import plane_scene, points

from jaxrender.scene import Material, with_effects
from jaxrender.shading import alpha_test, shade

_TOL = 1e-5


def test_lambert_plane_under_directional_light():
    rho = np.array([0.2, 0.5, 0.9])
    thetas = np.deg2rad([0.0, 30.0, 60.0, 85.0, 95.0])
    e = 3.0
    for th in thetas:
        scene = plane_scene([Material("m", albedo=tuple(rho))],
                            directional=[((np.sin(th), np.cos(th), 0.0), e)])
        got = np.asarray(shade(points(4, view=(0.3, 1.0, 0.2)), scene))
        want = rho / np.pi * e * max(np.cos(th), 0.0)
        np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), rtol=_TOL, atol=_TOL,
                                   err_msg=f"Lambert plane at theta={np.rad2deg(th):.0f} deg")


def test_point_light_inverse_square_falloff():
    rho, intensity = 0.7, 5.0
    for h, x in [(1.0, 0.0), (2.0, 0.0), (4.0, 1.0), (0.5, 3.0)]:
        scene = plane_scene([Material("m", albedo=(rho,) * 3)], point=[((x, h, 0.0), intensity)])
        got = np.asarray(shade(points(1), scene))[0]
        d2 = h * h + x * x
        want = rho / np.pi * intensity * (h / np.sqrt(d2)) / d2
        np.testing.assert_allclose(got, [want] * 3, rtol=_TOL, err_msg=f"point light at h={h} x={x}")


def test_ambient_and_emissive_add():
    scene = plane_scene([Material("m", albedo=(0.5, 0.25, 1.0), emissive=(0.1, 0.2, 0.3))],
                        ambient=0.4)
    got = np.asarray(shade(points(2), scene))
    np.testing.assert_allclose(got[0], [0.5 * 0.4 + 0.1, 0.25 * 0.4 + 0.2, 0.4 + 0.3], rtol=_TOL,
                               err_msg="ambient * albedo + emissive")
    off = np.asarray(shade(points(2), with_effects(scene, emissive=False)))
    np.testing.assert_allclose(off[0], [0.2, 0.1, 0.4], rtol=_TOL, err_msg="emissive switched off")


def test_blinn_phong_energy_normalised_peak_and_huge_exponents():
    e, ks = 2.0, 0.5
    for n in [1.0, 64.0, 1e4, 1e6]:
        scene = plane_scene([Material("m", albedo=(0.0,) * 3, specular=(ks,) * 3, shininess=n,
                                      brdf="blinn_phong")], directional=[((0.0, 1.0, 0.0), e)])
        # mirror configuration: l = v = n -> h = n, cos = 1
        peak = np.asarray(shade(points(1, view=(0, 1, 0)), scene))[0]
        np.testing.assert_allclose(peak, [ks * (n + 8) / (8 * np.pi) * e] * 3, rtol=1e-4,
                                   err_msg=f"Blinn-Phong peak at exponent {n}")
        grazing = np.asarray(shade(points(3, view=[(1, 0.01, 0), (0, -1, 1e-3), (1, 1, 0)]), scene))
        assert np.all(np.isfinite(grazing)), f"non-finite Blinn-Phong at exponent {n}: {grazing}"
        if n >= 1e4:
            assert grazing.max() < 1e-3, f"exponent {n} off the peak should be ~0: {grazing}"


def test_ggx_finite_and_reciprocal():
    mats = [Material("g", albedo=(0.0,) * 3, specular=(0.9, 0.6, 0.3), roughness=r, brdf="ggx")
            for r in (1e-3, 0.3, 1.0)]
    for k, m in enumerate(mats):
        a = plane_scene([m], directional=[((0.3, 0.8, 0.1), 1.0)])
        b = plane_scene([m], directional=[((0.5, 0.6, -0.2), 1.0)])
        # swap light and view: f(l, v) cos(l) E == f(v, l) cos(v) E up to the cosine ratio
        la, lb = np.array([0.3, 0.8, 0.1]), np.array([0.5, 0.6, -0.2])
        la, lb = la / np.linalg.norm(la), lb / np.linalg.norm(lb)
        fa = np.asarray(shade(points(1, view=lb), a))[0] / la[1]
        fb = np.asarray(shade(points(1, view=la), b))[0] / lb[1]
        assert np.all(np.isfinite(fa)) and np.all(fa >= 0), f"GGX roughness index {k}: {fa}"
        np.testing.assert_allclose(fa, fb, rtol=1e-4, err_msg=f"GGX reciprocity, material {k}")


def test_stripe_shader_is_int_texcoord_parity():
    res = 8.0
    scene = plane_scene([Material("s", albedo=(1.0,) * 3, procedural="stripes",
                                  stripe_resolution=res)], ambient=1.0)
    u = np.array([0.01, 0.13, 0.26, 0.37, 0.51, 0.99, -0.05, 12.3], np.float32)
    uv = np.stack([u, np.full_like(u, 0.3)], 1)
    got = np.asarray(shade(points(len(u), uv=uv), scene))[:, 0]
    want = (np.floor(u * res) % 2 == 0).astype(np.float32)
    np.testing.assert_array_equal(got, want, err_msg="IntTexCoord.x % 2 == 0 ? 1 : 0")


def test_alpha_test_follows_texture_alpha():
    img = np.ones((4, 4, 4))
    img[:, :2, 3] = 0.0  # left half transparent
    scene = plane_scene([Material("leaf", texture=0, alpha_tested=True, alpha_cutoff=0.5)],
                        textures=[img])
    assert scene.effects.alpha_test and scene.effects.textures
    uv = np.array([[0.1, 0.5], [0.9, 0.5], [0.2, 0.1], [0.8, 0.9]], np.float32)
    keep = np.asarray(alpha_test(points(4, uv=uv, duv=(1e-3, 0)), scene))
    np.testing.assert_array_equal(keep, [False, True, False, True], err_msg="alpha test")
    off = np.asarray(alpha_test(points(4, uv=uv), with_effects(scene, alpha_test=False)))
    assert off.all(), "alpha_test off must keep every valid point"


def test_invalid_points_shade_to_zero():
    scene = plane_scene(directional=[((0, 1, 0), 1.0)], ambient=1.0)
    p = points(3)
    p = type(p)(**{**p.__dict__, "valid": jnp.asarray([True, False, True])})
    got = np.asarray(shade(p, scene))
    assert np.all(got[1] == 0) and np.all(got[0] > 0), got


def test_view_depth_is_the_distance_along_the_camera_axis():
    from jaxrender.scene import look_at
    from jaxrender.shading import view_depth

    rng = np.random.default_rng(21)
    eye, target = rng.normal(size=3) * 3.0, rng.normal(size=3)
    camera = look_at(tuple(eye), tuple(target))
    pos = rng.normal(size=(9, 3)).astype(np.float32) * 4.0
    forward = (target - eye) / np.linalg.norm(target - eye)
    got = np.asarray(view_depth(points(9, position=pos), camera))
    np.testing.assert_allclose(got, (pos - eye) @ forward, rtol=1e-5, atol=1e-5,
                               err_msg="view_depth against (p - eye) . forward")
