"""Texture filtering against a plain NumPy reference; LOD formulas; normal-map edge cases."""

import jax
import jax.numpy as jnp
import numpy as np
from shading_helpers import plane_scene, points

from jaxrender.scene import Material
from jaxrender.scene.textures import pack_textures
from jaxrender.shading import shade
from jaxrender.shading.texture import lod_isotropic, sample

_TOL = 1e-5


def _ref_chain(img):
    chain = [img]
    while chain[-1].shape[0] > 1:
        a = chain[-1]
        chain.append(0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2]))
    return chain


def _ref_bilinear(level, u, v):
    s = level.shape[0]
    x, y = u * s - 0.5, (1.0 - v) * s - 0.5
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0
    t = lambda yy, xx: level[yy % s, xx % s]  # noqa: E731
    return ((1 - fy) * ((1 - fx) * t(y0, x0) + fx * t(y0, x0 + 1))
            + fy * ((1 - fx) * t(y0 + 1, x0) + fx * t(y0 + 1, x0 + 1)))


def _ref_trilinear(chain, u, v, dudx, dvdx, dudy, dvdy):
    r = chain[0].shape[0]
    rho = max(np.hypot(dudx * r, dvdx * r), np.hypot(dudy * r, dvdy * r))
    lod = np.clip(np.log2(max(rho, 1e-20)), 0, len(chain) - 1)
    l0 = int(np.floor(lod))
    l1 = min(l0 + 1, len(chain) - 1)
    t = lod - l0
    return (1 - t) * _ref_bilinear(chain[l0], u, v) + t * _ref_bilinear(chain[l1], u, v)


def test_trilinear_matches_numpy_reference():
    rng = np.random.default_rng(1)
    imgs = [rng.uniform(size=(16, 16, 4)) for _ in range(2)]
    tex = pack_textures(imgs)
    n = 64
    uv = rng.uniform(-2, 3, size=(n, 2)).astype(np.float32)
    scale = 10.0 ** rng.uniform(-3, 0.5, size=(n, 1))
    dx = (rng.normal(size=(n, 2)) * scale).astype(np.float32)
    dy = (rng.normal(size=(n, 2)) * scale).astype(np.float32)
    tid = rng.integers(0, 2, n).astype(np.int32)
    got = np.asarray(jax.jit(sample)(tex, jnp.asarray(tid), jnp.asarray(uv), jnp.asarray(dx),
                                     jnp.asarray(dy)))
    chains = [_ref_chain(im.astype(np.float64)) for im in imgs]
    want = np.array([_ref_trilinear(chains[tid[i]], *uv[i], *dx[i], *dy[i]) for i in range(n)])
    np.testing.assert_allclose(got, want, atol=2e-5, err_msg="trilinear vs NumPy reference")


def test_anisotropic_taps_average_along_major_axis():
    rng = np.random.default_rng(2)
    img = rng.uniform(size=(16, 16, 4))
    tex = pack_textures([img])
    chain = _ref_chain(img)
    uv = np.array([[0.3, 0.6]], np.float32)
    dx, dy = np.array([[0.25, 0.0]], np.float32), np.array([[0.0, 1.0 / 64]], np.float32)
    taps = 4
    got = np.asarray(sample(tex, jnp.zeros(1, jnp.int32), jnp.asarray(uv), jnp.asarray(dx),
                            jnp.asarray(dy), aniso_taps=taps))[0]
    # major 4 texels, minor 0.25 texels -> LOD log2(max(0.25, 4 / 4)) = 0, taps on level 0
    offs = [((i + 0.5) / taps - 0.5) * 0.25 for i in range(taps)]
    want = np.mean([_ref_bilinear(chain[0], uv[0, 0] + o, uv[0, 1]) for o in offs], axis=0)
    np.testing.assert_allclose(got, want, atol=_TOL, err_msg="anisotropic taps")


def test_lod_is_log2_of_longer_footprint_axis():
    r = 256
    dx = jnp.asarray([[1.0 / r, 0.0], [4.0 / r, 0.0], [0.0, 0.0], [3.0 / r, 4.0 / r]])
    dy = jnp.asarray([[0.0, 1.0 / r], [0.0, 1.0 / r], [0.0, 16.0 / r], [0.0, 0.0]])
    got = np.asarray(lod_isotropic(dx, dy, r))
    np.testing.assert_allclose(got, [0.0, 2.0, 4.0, np.log2(5.0)], atol=_TOL, err_msg="GL LOD")


def test_zero_length_normal_map_normals_stay_finite():
    flat = np.concatenate([np.full((8, 8, 3), 0.5), np.ones((8, 8, 1))], -1)  # decodes to 0
    scene = plane_scene([Material("nm", albedo=(0.5,) * 3, normal_map=0, specular=(0.5,) * 3,
                                  shininess=1e6, brdf="blinn_phong")],
                        textures=[flat], directional=[((0.2, 1.0, 0.0), 1.0)])
    assert scene.effects.normal_map
    for toksvig in (False, True):
        eff = scene.effects.replace(toksvig=toksvig)
        got = np.asarray(shade(points(5, view=(0.1, 1, 0), duv=(0.3, 0.0)), scene, eff))
        assert np.all(np.isfinite(got)), f"toksvig={toksvig}: {got}"
        # The vertex normal is used instead; Toksvig reads the zero length as maximal variance
        # (the exponent drops to ~0), which is the same as shininess 0 without the normal map.
        ref = scene
        if toksvig:
            ref = plane_scene([Material("r", albedo=(0.5,) * 3, specular=(0.5,) * 3, shininess=0.0,
                                        brdf="blinn_phong")], directional=[((0.2, 1.0, 0.0), 1.0)])
        plain = np.asarray(shade(points(5, view=(0.1, 1, 0)), ref, ref.effects.replace(normal_map=False)))
        np.testing.assert_allclose(got, plain, rtol=1e-4, atol=_TOL,
                                   err_msg=f"zero normal-map normal, toksvig={toksvig}")


def test_toksvig_lowers_the_peak_of_a_filtered_bumpy_normal_map():
    y, x = np.mgrid[0:16, 0:16]
    tilt = np.where((x + y) % 2 == 0, 0.6, -0.6)  # alternating normals: the MIP average shortens
    n = np.stack([tilt, np.zeros_like(tilt), np.ones_like(tilt)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    img = np.concatenate([n * 0.5 + 0.5, np.ones((16, 16, 1))], -1)
    scene = plane_scene([Material("nm", albedo=(0.0,) * 3, normal_map=0, specular=(1.0,) * 3,
                                  shininess=2000.0, brdf="blinn_phong")],
                        textures=[img], directional=[((0.0, 1.0, 0.0), 1.0)])
    p = points(1, view=(0, 1, 0), duv=(1.0, 0.0))  # whole texture in one pixel: 1x1 level
    plain = float(np.asarray(shade(p, scene))[0, 0])
    tok = float(np.asarray(shade(p, scene, scene.effects.replace(toksvig=True)))[0, 0])
    assert np.isfinite(tok) and tok < 0.5 * plain, (plain, tok)


def test_far_texel_coordinates_wrap_exactly():
    # uvs far from the origin (a ground plane to the horizon): the texel coordinate is wrapped
    # before the int cast. Oracle: the same float32 coordinate, wrapped with Python's exact
    # integer modulo, bilinear at level 0 (tiny derivatives).
    rng = np.random.default_rng(5)
    img = rng.uniform(size=(16, 16, 4))
    tex = pack_textures([img])
    n = 200
    uv = (rng.uniform(-1, 1, size=(n, 2)) * 10.0 ** rng.uniform(0, 7, size=(n, 1))
          ).astype(np.float32)
    tiny = np.full((n, 2), 1e-6, np.float32)
    got = np.asarray(jax.jit(sample)(tex, jnp.zeros(n, jnp.int32), jnp.asarray(uv),
                                     jnp.asarray(tiny), jnp.asarray(tiny)))
    s = np.float32(16)
    want = []
    for u, v in uv:
        tx, ty = u * s - np.float32(0.5), (np.float32(1) - v) * s - np.float32(0.5)
        x0f, y0f = np.floor(tx), np.floor(ty)
        fx, fy = float(tx - x0f), float(ty - y0f)
        x0, y0 = int(x0f) % 16, int(y0f) % 16
        t = lambda yy, xx: img[yy % 16, xx % 16]  # noqa: E731
        want.append((1 - fy) * ((1 - fx) * t(y0, x0) + fx * t(y0, x0 + 1))
                    + fy * ((1 - fx) * t(y0 + 1, x0) + fx * t(y0 + 1, x0 + 1)))
    np.testing.assert_allclose(got, np.array(want), atol=2e-5,
                               err_msg="far texel coordinates vs exact integer wrap")
