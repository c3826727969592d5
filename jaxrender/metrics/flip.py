"""FLIP (Andersson et al., HPG 2020; HDR-FLIP, EGSR 2021) in JAX.

A port of NVIDIA's FLIP (BSD-3-Clause, https://github.com/NVlabs/flip, ``FLIP.h`` of
flip-evaluator 1.7) with its defaults: 67.02 pixels per degree (0.7 m from a 0.7 m wide, 3840
pixel display), separable spatial filters, clamp-to-edge borders.

LDR-FLIP, per pixel:
  1. sRGB inputs -> linear, clamp to [0, 1] -> YCxCz (opponent space, D65).
  2. Colour pipeline: filter Y, Cx with one Gaussian each and Cz with a sum of two (contrast
     sensitivity), back to linear RGB, clamp, CIELab, Hunt-adjust a and b by L, HyAB distance,
     raise to 0.7 and remap so that 0.4 of the largest distance (green-blue) maps to 0.95.
  3. Feature pipeline: first and second Gaussian derivatives of the normalised Y channel (edges and
     points), difference of their magnitudes, normalised and square-rooted.
  4. FLIP = colour ** (1 - feature).
HDR-FLIP tone-maps exposures from start to stop (computed from the reference's luminance, or
given) and keeps the per-pixel maximum of LDR-FLIP over them.
"""

from __future__ import annotations

import math
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.metrics._common import (
    Array,
    correlate_valid,
    map_frames,
    pad_axis,
    precision,
    prepare,
    spatial_mean,
)
from jaxrender.metrics.display import srgb_decode

# Viewing conditions: 0.7 m to a 0.7 m wide, 3840 pixel display.
DEFAULT_PPD = 0.7 * (3840.0 / 0.7) * (math.pi / 180.0)  # 67.0206...

# FLIP constants (paper, Table 1).
GQC = 0.7  # colour difference exponent
GPC = 0.4  # colour difference remap breakpoint (fraction of the max)
GPT = 0.95  # value the breakpoint maps to
GW = 0.082  # feature filter width, degrees
GQF = 0.5  # feature difference exponent

# Contrast sensitivity: sums of Gaussians a * sqrt(pi / b) * exp(-pi^2 x^2 / b) per channel.
CSF_A1 = (1.0, 1.0, 34.1)
CSF_B1 = (0.0047, 0.0053, 0.04)
CSF_A2 = (0.0, 0.0, 13.5)
CSF_B2 = (1.0e-5, 1.0e-5, 0.025)

# Linear sRGB <-> XYZ (D65) exactly as FLIP writes them, and the D65 white it normalises by.
RGB_TO_XYZ = np.array([
    [10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0],
    [2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0],
    [1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0],
])
XYZ_TO_RGB = np.array([
    [3.241003275, -1.537398934, -0.498615861],
    [-0.969224334, 1.875930071, 0.041554224],
    [0.055639423, -0.204011202, 1.057148933],
])
WHITE_D65 = np.array([0.950428545, 1.0, 1.088900371])
INV_WHITE_D65 = np.array([1.052156925, 1.0, 0.918357670])

# Tone mappers of HDR-FLIP: (c^2 t0 + c t1 + t2) / (c^2 t3 + c t4 + t5), Reinhard on luminance.
TONEMAPPERS = {
    "reinhard": (0.0, 1.0, 0.0, 0.0, 1.0, 1.0),
    "aces": (0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14),
    "hable": (0.231683, 0.013791, 0.0, 0.18, 0.3, 0.018),
}
LUMINANCE = (0.2126, 0.7152, 0.0722)
MODES = ("ldr", "hdr")
FRAMES_PER_CHUNK = 4


# ---------------------------------------------------------------------------------------------
# Colour spaces (elementwise, last axis = 3 channels).


def _mat3(x: Array, m: np.ndarray) -> Array:
    """Apply a 3x3 matrix to the last axis with elementwise products (no TF32 matmul)."""
    c = [x[..., i] for i in range(3)]
    rows = [m[r, 0] * c[0] + m[r, 1] * c[1] + m[r, 2] * c[2] for r in range(3)]
    return jnp.stack(rows, axis=-1)


def _scale3(x: Array, s: np.ndarray) -> Array:
    return jnp.stack([x[..., i] * s[i] for i in range(3)], axis=-1)


def linear_rgb_to_ycxcz(rgb: Array) -> Array:
    xyz = _scale3(_mat3(rgb, RGB_TO_XYZ), INV_WHITE_D65)
    y, x, z = xyz[..., 1], xyz[..., 0], xyz[..., 2]
    return jnp.stack([116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)], axis=-1)


def ycxcz_to_linear_rgb(ycxcz: Array) -> Array:
    y = (ycxcz[..., 0] + 16.0) / 116.0
    x = y + ycxcz[..., 1] / 500.0
    z = y - ycxcz[..., 2] / 200.0
    xyz = _scale3(jnp.stack([x, y, z], axis=-1), WHITE_D65)
    return _mat3(xyz, XYZ_TO_RGB)


def _lab_f(t: Array) -> Array:
    delta = 6.0 / 29.0
    return jnp.where(t > delta**3, jnp.cbrt(t), t / (3.0 * delta * delta) + 4.0 / 29.0)


def linear_rgb_to_lab(rgb: Array) -> Array:
    """CIELab (D65) of linear RGB, as FLIP computes it."""
    xyz = _scale3(_mat3(rgb, RGB_TO_XYZ), INV_WHITE_D65)
    fx, fy, fz = _lab_f(xyz[..., 0]), _lab_f(xyz[..., 1]), _lab_f(xyz[..., 2])
    return jnp.stack([116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)], axis=-1)


def _hunt_hyab(lab_ref: Array, lab_test: Array) -> Array:
    """HyAB distance after the Hunt adjustment (a, b scaled by 0.01 L)."""
    def hunt(lab):
        s = 0.01 * lab[..., 0]
        return lab[..., 0], s * lab[..., 1], s * lab[..., 2]

    l1, a1, b1 = hunt(lab_ref)
    l2, a2, b2 = hunt(lab_test)
    return jnp.abs(l1 - l2) + jnp.sqrt((a1 - a2) * (a1 - a2) + (b1 - b2) * (b1 - b2))


def _max_colour_distance() -> float:
    """HyAB^GQC between Hunt-adjusted pure green and pure blue: the largest colour difference."""
    def lab(rgb):
        xyz = RGB_TO_XYZ @ np.asarray(rgb, np.float64) * INV_WHITE_D65
        d = 6.0 / 29.0
        f = np.where(xyz > d**3, np.cbrt(xyz), xyz / (3 * d * d) + 4.0 / 29.0)
        L = 116.0 * f[1] - 16.0
        return np.array([L, 0.01 * L * 500.0 * (f[0] - f[1]), 0.01 * L * 200.0 * (f[1] - f[2])])

    g, b = lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])
    return float((abs(g[0] - b[0]) + np.hypot(g[1] - b[1], g[2] - b[2])) ** GQC)


# ---------------------------------------------------------------------------------------------
# Filters (built in float64 on the host, cast to the working dtype).


def spatial_filter_radius(ppd: float) -> int:
    b_max = max(max(CSF_B1), max(CSF_B2))
    return int(math.ceil(3.0 * math.sqrt(b_max / (2.0 * math.pi * math.pi)) * ppd))


def spatial_taps(ppd: float) -> np.ndarray:
    """(n, 4) separable taps for [Y, Cx, Cz first Gaussian, Cz second Gaussian].

    Y and Cx are single Gaussians normalised to sum 1. Cz's filter is a sum of two 2-D Gaussians,
    split into two separable filters whose 1-D taps are the square roots of each term; both are
    scaled so that the 2-D sum of the pair is 1."""
    r = spatial_filter_radius(ppd)
    x = np.arange(-r, r + 1, dtype=np.float64) / ppd
    x2 = x * x
    pi2 = math.pi * math.pi

    def gauss(a, b):
        return a * math.sqrt(math.pi / b) * np.exp(-pi2 * x2 / b)

    def gauss_sqrt(a, b):
        return math.sqrt(a * math.sqrt(math.pi / b)) * np.exp(-pi2 * x2 / b)

    gy, gcx = gauss(CSF_A1[0], CSF_B1[0]), gauss(CSF_A1[1], CSF_B1[1])
    gz1, gz2 = gauss_sqrt(CSF_A1[2], CSF_B1[2]), gauss_sqrt(CSF_A2[2], CSF_B2[2])
    norm_z = 1.0 / math.sqrt(gz1.sum() ** 2 + gz2.sum() ** 2)
    return np.stack([gy / gy.sum(), gcx / gcx.sum(), gz1 * norm_z, gz2 * norm_z], axis=-1)


def feature_taps(ppd: float) -> np.ndarray:
    """(n, 3) taps [Gaussian, first derivative, second derivative], sigma = GW / 2 degrees.

    The Gaussian sums to 1; the positive and the negative lobes of each derivative sum to +1
    and -1."""
    sd = 0.5 * GW * ppd
    r = int(math.ceil(3.0 * sd))
    x = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-(x * x) / (2.0 * sd * sd))
    dg = -x * g
    ddg = (x * x / (sd * sd) - 1.0) * g

    def lobes(w):
        pos, neg = w[w > 0].sum(), -w[w <= 0].sum()
        return np.where(w > 0, w / pos, w / neg)

    return np.stack([g / g.sum(), lobes(dg), lobes(ddg)], axis=-1)


def _separable(x: Array, taps_w: Array, taps_h: Array) -> Array:
    """Clamp-to-edge correlation of (..., H, W, C): first along W, then along H."""
    rw, rh = (taps_w.shape[0] - 1) // 2, (taps_h.shape[0] - 1) // 2
    x = correlate_valid(pad_axis(x, rw, -2, "edge"), taps_w, -2)
    return correlate_valid(pad_axis(x, rh, -3, "edge"), taps_h, -3)


# ---------------------------------------------------------------------------------------------
# LDR-FLIP on linear [0, 1] inputs.


def _colour_difference(ycxcz: Array, ppd: float) -> Array:
    """Colour pipeline of a (reference, test) pair (2, ..., H, W, 3) in YCxCz -> (..., H, W)."""
    st = jnp.asarray(spatial_taps(ppd), ycxcz.dtype)
    chans = jnp.stack([ycxcz[..., 0], ycxcz[..., 1], ycxcz[..., 2], ycxcz[..., 2]], axis=-1)
    f = _separable(chans, st, st)
    filtered = jnp.stack([f[..., 0], f[..., 1], f[..., 2] + f[..., 3]], axis=-1)
    lab = linear_rgb_to_lab(jnp.clip(ycxcz_to_linear_rgb(filtered), 0.0, 1.0))
    # Where both filtered colours are bitwise equal the distance is 0 exactly: XLA may round the
    # two halves of one fused expression differently (an ulp of L is ~1e-5 of FLIP).
    same = jnp.all(filtered[0] == filtered[1], axis=-1)
    dist = jnp.where(same, 0.0, jnp.power(_hunt_hyab(lab[0], lab[1]), GQC))
    cmax = _max_colour_distance()
    pccmax = GPC * cmax
    return jnp.where(dist < pccmax, dist * (GPT / pccmax),
                     GPT + (dist - pccmax) / (cmax - pccmax) * (1.0 - GPT))


def _feature_difference(ycxcz: Array, ppd: float) -> Array:
    """Feature (edge and point) pipeline of a pair in YCxCz -> (..., H, W)."""
    ft = jnp.asarray(feature_taps(ppd), ycxcz.dtype)  # columns: g, dg, ddg
    y = (ycxcz[..., 0] * (1.0 / 116.0) + 16.0 / 116.0)[..., None]  # Y normalised to [0, 1]
    r = (ft.shape[0] - 1) // 2
    # Along W: the Gaussian, first and second derivative of each row.
    yx = correlate_valid(pad_axis(jnp.concatenate([y, y, y], -1), r, -2, "edge"), ft, -2)
    # Along H: Gaussian of (dx, ddx); first and second derivative of the W-Gaussian.
    taps_h = jnp.stack([ft[:, 0], ft[:, 0], ft[:, 1], ft[:, 2]], axis=-1)
    stack_h = jnp.stack([yx[..., 1], yx[..., 2], yx[..., 0], yx[..., 0]], axis=-1)
    d = correlate_valid(pad_axis(stack_h, r, -3, "edge"), taps_h, -3)
    dx, ddx, dy, ddy = d[..., 0], d[..., 1], d[..., 2], d[..., 3]
    edge = jnp.sqrt(dx * dx + dy * dy)
    point = jnp.sqrt(ddx * ddx + ddy * ddy)
    same = jnp.all(d[0] == d[1], axis=-1)
    diff = jnp.where(same, 0.0,
                     jnp.maximum(jnp.abs(edge[0] - edge[1]), jnp.abs(point[0] - point[1])))
    return jnp.power(diff * (1.0 / math.sqrt(2.0)), GQF)


def _ldr_flip_linear(pair: Array, ppd: float) -> Array:
    """FLIP map (..., H, W) of a stacked (reference, test) pair (2, ..., H, W, 3) of linear RGB
    images already in [0, 1]."""
    ycxcz = linear_rgb_to_ycxcz(pair)
    with jax.named_scope("flip_colour"):
        colour = _colour_difference(ycxcz, ppd)
    with jax.named_scope("flip_feature"):
        feature = _feature_difference(ycxcz, ppd)
    return jnp.power(colour, 1.0 - feature)


# ---------------------------------------------------------------------------------------------
# HDR-FLIP.


def _tonemap(x: Array, name: str) -> Array:
    if name == "reinhard":
        lum = LUMINANCE[0] * x[..., 0] + LUMINANCE[1] * x[..., 1] + LUMINANCE[2] * x[..., 2]
        return x / (1.0 + lum)[..., None]
    t = TONEMAPPERS[name]
    return (x * x * t[0] + x * t[1] + t[2]) / (x * x * t[3] + x * t[4] + t[5])


def _tonemap_knee(name: str) -> float:
    """The linear value the tone mapper maps to 0.85 (FLIP's exposure anchor)."""
    t0, t1, t2, t3, t4, t5 = TONEMAPPERS[name]
    target = 0.85
    a, b, c = t0 - target * t3, t1 - target * t4, t2 - target * t5
    if a == 0.0:
        return -c / b
    mid = -0.5 * (b / a)
    return mid + math.sqrt(mid * mid - c / a)


def exposure_range(reference: Array, tonemapper: str = "aces") -> tuple[Array, Array]:
    """HDR-FLIP's automatic exposure range of a linear reference (..., H, W, 3): start maps the
    brightest pixel and stop the median luminance to the tone mapper's 0.85 point.

    FLIP leaves a median (or maximum) luminance of 0 undefined (an infinite range); here a zero
    median falls back to the smallest non-zero luminance, and an all-black reference gets the
    range [0, 0]."""
    lum = (LUMINANCE[0] * reference[..., 0] + LUMINANCE[1] * reference[..., 1]
           + LUMINANCE[2] * reference[..., 2])
    flat = lum.reshape(lum.shape[:-2] + (-1,))
    n = flat.shape[-1]
    median = jnp.sort(flat, axis=-1)[..., n // 2]  # FLIP: nth_element at n / 2
    y_max = jnp.max(flat, axis=-1)
    y_min_nonzero = jnp.min(jnp.where(flat != 0.0, flat, jnp.inf), axis=-1)
    median = jnp.where(median > 0.0, median, y_min_nonzero)
    knee = _tonemap_knee(tonemapper)
    ok = (y_max > 0.0) & (median > 0.0) & jnp.isfinite(median)
    start = jnp.where(ok, jnp.log2(knee / jnp.where(ok, y_max, 1.0)), 0.0)
    stop = jnp.where(ok, jnp.log2(knee / jnp.where(ok, median, 1.0)), 0.0)
    return start, stop


def _hdr_flip(pair, ppd, tonemapper, start_exposure, stop_exposure, num_exposures):
    auto_start, auto_stop = exposure_range(pair[0], tonemapper)
    dt = pair.dtype
    start = auto_start if start_exposure is None else jnp.full_like(auto_start, start_exposure)
    stop = auto_stop if stop_exposure is None else jnp.full_like(auto_stop, stop_exposure)
    if num_exposures is None:
        num = jnp.maximum(2.0, jnp.ceil(stop - start)).astype(jnp.int32)
    else:
        num = jnp.full(start.shape, num_exposures, jnp.int32)
    step = (stop - start) / (num - 1).astype(dt)

    def expand(v):  # (...) -> (1, ..., 1, 1, 1), against the stacked pair
        return v.reshape((1,) + v.shape + (1, 1, 1))

    def body(state):
        i, err = state
        exposure = start + i.astype(dt) * step
        scale = expand(jnp.exp2(exposure))
        e = _ldr_flip_linear(jnp.clip(_tonemap(pair * scale, tonemapper), 0.0, 1.0), ppd)
        active = (i < num).reshape(num.shape + (1, 1))
        return i + 1, jnp.where(active, jnp.maximum(err, e), err)

    err0 = jnp.zeros(pair.shape[1:-1], dt)
    _, err = jax.lax.while_loop(lambda s: s[0] < jnp.max(num), body, (jnp.int32(0), err0))
    return err


@partial(jax.jit, static_argnames=("mode", "ppd", "srgb", "tonemapper", "start_exposure",
                                   "stop_exposure", "num_exposures"))
def _flip(ref, test, mode, ppd, srgb, tonemapper, start_exposure, stop_exposure,
          num_exposures):
    def per_chunk(r, t):
        pair = jnp.stack([r, t])
        if mode == "ldr":
            if srgb:
                pair = srgb_decode(pair)
            fmap = _ldr_flip_linear(jnp.clip(pair, 0.0, 1.0), ppd)
        else:
            fmap = _hdr_flip(pair, ppd, tonemapper, start_exposure, stop_exposure,
                             num_exposures)
        return spatial_mean(fmap, 2), fmap

    return map_frames(per_chunk, (ref, test), FRAMES_PER_CHUNK)


def flip(reference, test, mode: str = "ldr", *, ppd: float = DEFAULT_PPD, srgb: bool = True,
         tonemapper: str = "aces", start_exposure: float | None = None,
         stop_exposure: float | None = None, num_exposures: int | None = None,
         dtype=jnp.float32) -> tuple[Array, Array]:
    """FLIP error of ``test`` against ``reference``: (mean per image, map (..., H, W)).

    mode="ldr": inputs sRGB-encoded in [0, 1] (``srgb=False`` for linear [0, 1] inputs), as
    ``flip_evaluator.evaluate(ref, test, "LDR")``. mode="hdr": linear, non-negative inputs;
    exposures from ``start_exposure`` to ``stop_exposure`` in ``num_exposures`` steps, each
    computed from the reference when not given, as ``flip_evaluator.evaluate(..., "HDR")``.
    """
    mode = mode.lower()
    if mode not in MODES:
        raise ValueError(f"flip: mode must be one of {MODES}, got {mode!r}")
    tonemapper = tonemapper.lower()
    if tonemapper not in TONEMAPPERS:
        raise ValueError(
            f"flip: tonemapper must be one of {tuple(TONEMAPPERS)}, got {tonemapper!r}")
    if not ppd > 0.0:
        raise ValueError(f"flip: ppd must be positive, got {ppd}")
    if start_exposure is not None and stop_exposure is not None and start_exposure > stop_exposure:
        raise ValueError("flip: start_exposure must not exceed stop_exposure")
    if num_exposures is not None and num_exposures < 2:
        raise ValueError(f"flip: num_exposures must be at least 2, got {num_exposures}")
    with precision(dtype):
        r, t = prepare("flip", reference, test, dtype)
        return _flip(r, t, mode, float(ppd), bool(srgb), tonemapper,
                     None if start_exposure is None else float(start_exposure),
                     None if stop_exposure is None else float(stop_exposure),
                     None if num_exposures is None else int(num_exposures))
