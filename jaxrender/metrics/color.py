"""CIEDE2000 colour difference of sRGB images, equal to colour-science.

sRGB-encoded [0, 1] -> linear (IEC 61966-2-1) -> CIE XYZ with colour-science's sRGB matrix ->
CIELab relative to the sRGB white (CIE 1931 2 degree D65, xy = 0.3127, 0.3290) -> CIEDE2000
(Sharma, Wu & Dalal 2005) with k_L = k_C = k_H = 1. The branch rules for hue (zero chroma, the
180 degree wrap) follow ``colour.difference.delta_E_CIE2000``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.metrics._common import Array, map_frames, precision, prepare, spatial_mean

# colour-science 0.4: RGB_COLOURSPACE_sRGB.matrix_RGB_to_XYZ (IEC 61966-2-1, rounded).
SRGB_TO_XYZ = np.array([
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
])
D65_XY = (0.3127, 0.3290)
WHITE_XYZ = np.array([D65_XY[0] / D65_XY[1], 1.0, (1.0 - D65_XY[0] - D65_XY[1]) / D65_XY[1]])
# colour-science's decoding switches branch at the encoded value of 0.0031308.
SRGB_DECODE_CUTOFF = 0.0031308 * 12.92
FRAMES_PER_CHUNK = 8


def _srgb_decode(v: Array) -> Array:
    safe = jnp.maximum(v, SRGB_DECODE_CUTOFF)
    return jnp.where(v <= SRGB_DECODE_CUTOFF, v / 12.92, jnp.power((safe + 0.055) / 1.055, 2.4))


LAB_EPSILON = (24.0 / 116.0) ** 3  # CIE 1976: cube root above, linear segment below


def _lab_f(t: Array) -> Array:
    return jnp.where(t > LAB_EPSILON, jnp.cbrt(t), (841.0 / 108.0) * t + 16.0 / 116.0)


def _lab_f_diff(u: Array, v: Array, u_minus_v: Array) -> Array:
    """f(u) - f(v) without cancellation: near-neutral colours have f(u) ~ f(v), and a and b are
    500x and 200x that small difference. On the cube-root branch it is
    (u - v) / (cu^2 + cu cv + cv^2) with ``u_minus_v`` formed directly from linear RGB."""
    cu, cv = jnp.cbrt(u), jnp.cbrt(v)
    both_cbrt = (u > LAB_EPSILON) & (v > LAB_EPSILON)
    return jnp.where(both_cbrt, u_minus_v / (cu * cu + cu * cv + cv * cv), _lab_f(u) - _lab_f(v))


def srgb_to_lab(rgb: Array) -> Array:
    """CIELab (D65) of sRGB-encoded (..., 3) values, as colour-science's
    ``XYZ_to_Lab(sRGB_to_XYZ(rgb))``."""
    lin = _srgb_decode(rgb)
    c = [lin[..., i] for i in range(3)]

    def combo(m):  # elementwise m . rgb (no TF32 matmul)
        return m[0] * c[0] + m[1] * c[1] + m[2] * c[2]

    # X/Xn, Y/Yn, Z/Zn and their differences, each from its own float64 coefficients.
    rows = SRGB_TO_XYZ / WHITE_XYZ[:, None]
    x, y, z = combo(rows[0]), combo(rows[1]), combo(rows[2])
    fy = _lab_f(y)
    return jnp.stack([116.0 * fy - 16.0,
                      500.0 * _lab_f_diff(x, y, combo(rows[0] - rows[1])),
                      200.0 * _lab_f_diff(y, z, combo(rows[1] - rows[2]))], axis=-1)


def _hue_deg(b: Array, a: Array) -> Array:
    h = jnp.degrees(jnp.arctan2(b, a)) % 360.0
    return jnp.where((b == 0.0) & (a == 0.0), 0.0, h)


def ciede2000(lab1: Array, lab2: Array) -> Array:
    """CIEDE2000 of (..., 3) CIELab arrays (k_L = k_C = k_H = 1)."""
    l1, a1, b1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    l2, a2, b2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]
    pow25_7 = 25.0**7

    c_bar = 0.5 * (jnp.hypot(a1, b1) + jnp.hypot(a2, b2))
    c_bar7 = c_bar**7
    g = 0.5 * (1.0 - jnp.sqrt(c_bar7 / (c_bar7 + pow25_7)))
    a1p, a2p = (1.0 + g) * a1, (1.0 + g) * a2
    c1p, c2p = jnp.hypot(a1p, b1), jnp.hypot(a2p, b2)
    h1p, h2p = _hue_deg(b1, a1p), _hue_deg(b2, a2p)

    dl = l2 - l1
    dc = c2p - c1p
    c_prod = c1p * c2p
    dh_raw = h2p - h1p
    dh = jnp.where(
        c_prod == 0.0, 0.0,
        jnp.where(jnp.abs(dh_raw) <= 180.0, dh_raw,
                  jnp.where(dh_raw > 180.0, dh_raw - 360.0, dh_raw + 360.0)))
    d_hue = 2.0 * jnp.sqrt(c_prod) * jnp.sin(jnp.radians(0.5 * dh))

    l_bar = 0.5 * (l1 + l2)
    c_bar_p = 0.5 * (c1p + c2p)
    h_sum = h1p + h2p
    h_absdiff = jnp.abs(h1p - h2p)
    h_bar = jnp.where(
        c_prod == 0.0, h_sum,
        jnp.where(h_absdiff <= 180.0, 0.5 * h_sum,
                  jnp.where(h_sum < 360.0, 0.5 * (h_sum + 360.0), 0.5 * (h_sum - 360.0))))

    t = (1.0 - 0.17 * jnp.cos(jnp.radians(h_bar - 30.0))
         + 0.24 * jnp.cos(jnp.radians(2.0 * h_bar))
         + 0.32 * jnp.cos(jnp.radians(3.0 * h_bar + 6.0))
         - 0.20 * jnp.cos(jnp.radians(4.0 * h_bar - 63.0)))
    d_theta = 30.0 * jnp.exp(-(((h_bar - 275.0) / 25.0) ** 2))
    c_bar_p7 = c_bar_p**7
    r_c = 2.0 * jnp.sqrt(c_bar_p7 / (c_bar_p7 + pow25_7))
    l50 = (l_bar - 50.0) ** 2
    s_l = 1.0 + 0.015 * l50 / jnp.sqrt(20.0 + l50)
    s_c = 1.0 + 0.045 * c_bar_p
    s_h = 1.0 + 0.015 * c_bar_p * t
    r_t = -jnp.sin(jnp.radians(2.0 * d_theta)) * r_c

    tl, tc, th = dl / s_l, dc / s_c, d_hue / s_h
    return jnp.sqrt(tl * tl + tc * tc + th * th + r_t * tc * th)


@jax.jit
def _delta_e(a: Array, b: Array):
    def per_chunk(x, y):
        with jax.named_scope("ciede2000"):
            de = ciede2000(srgb_to_lab(x), srgb_to_lab(y))
        return spatial_mean(de, 2), de

    return map_frames(per_chunk, (a, b), FRAMES_PER_CHUNK)


def delta_e2000(a, b, *, dtype=jnp.float32) -> tuple[Array, Array]:
    """CIEDE2000 between sRGB-encoded images in [0, 1]: (mean per image, map (..., H, W))."""
    with precision(dtype):
        a, b = prepare("delta_e2000", a, b, dtype)
        return _delta_e(a, b)
