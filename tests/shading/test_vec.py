"""The per-point component helpers (``shading.vec``) against NumPy on fresh vectors, the
degenerate ones included: zero length, non-finite components, parallel pairs."""

import jax
import numpy as np

from jaxrender.shading.vec import components, cross3, dot3, normalize3, stack


def _vectors(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3)).astype(np.float32) * rng.uniform(1e-3, 1e3, (n, 1))
    v[0] = 0.0  # zero length: the fallback
    v[1] = [np.inf, 1.0, 0.0]  # not finite: the fallback
    v[2] = [np.nan, 0.0, 0.0]
    v[3] = 1e-20  # |v|^2 underflows: the fallback
    return v.astype(np.float32)


def test_components_agree_with_numpy():
    a, b = _vectors(64, 3), _vectors(64, 4)
    a[10] = [1.0, 2.0, 3.0]
    b[10] = 2.5 * a[10]  # parallel: a zero cross product, exact in float32
    fallback = _vectors(64, 5)
    fallback[:4] = [0.0, 0.0, 1.0]
    dot, cross, unit, back = jax.jit(lambda x, y, f: (
        dot3(components(x), components(y)), stack(cross3(components(x), components(y))),
        stack(normalize3(components(x), components(f))), stack(components(x))))(a, b, fallback)
    with np.errstate(invalid="ignore", over="ignore"):  # the non-finite rows
        want_dot = (a * b).sum(axis=1)
        want_cross = np.cross(a, b)
        length2 = (a.astype(np.float64) ** 2).sum(axis=1)
        ok = np.isfinite(length2) & (length2 > 1e-30)
        want_unit = np.where(ok[:, None], a / np.sqrt(np.where(ok, length2, 1.0))[:, None],
                             fallback)
    rows = slice(4, None)  # the finite ones
    np.testing.assert_allclose(dot[rows], want_dot[rows], rtol=1e-5, atol=1e-3,
                               err_msg="dot3 is the row-wise dot product")
    np.testing.assert_allclose(cross[rows], want_cross[rows], rtol=1e-5, atol=1e-3,
                               err_msg="cross3 is the cross product")
    np.testing.assert_array_equal(cross[10], 0.0, err_msg="parallel vectors")
    np.testing.assert_allclose(unit, want_unit, rtol=1e-6, atol=1e-6,
                               err_msg="normalize3: unit length, or the fallback")
    np.testing.assert_array_equal(unit[:4], fallback[:4],
                                  err_msg="zero, infinite, NaN and underflowing rows fall back")
    np.testing.assert_array_equal(back, a, err_msg="stack(components(x)) is x")


def test_a_scalar_component_broadcasts_like_the_array_it_stands_for():
    # A directional light's direction is three scalars beside the points' [N] components.
    points = _vectors(32, 6)[4:]
    light = np.asarray([0.3, -0.8, 0.5], np.float32)
    dot, cross, unit = jax.jit(lambda p, l: (
        dot3(components(p), components(l)), stack(cross3(components(p), components(l))),
        stack(normalize3(components(l), components(l)))))(points, light)
    np.testing.assert_allclose(dot, points @ light, rtol=1e-5, atol=1e-3,
                               err_msg="dot3 of [N] components with scalars")
    np.testing.assert_allclose(cross, np.cross(points, light), rtol=1e-5, atol=1e-3,
                               err_msg="cross3 of [N] components with scalars")
    np.testing.assert_allclose(unit, light / np.linalg.norm(light), rtol=1e-6,
                               err_msg="normalize3 of scalars")
