"""Lights: directional (the first one may cast a shadow map), point (many), ambient."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.types import Array, pytree_dataclass


@pytree_dataclass
class Lights:
    """dir_to_light float32[Ld,3] unit vectors from the surface towards each directional light;
    dir_irradiance float32[Ld,3] irradiance E on a surface facing the light (W/m^2 per channel);
    point_position float32[Lp,3]; point_intensity float32[Lp,3] radiant intensity I (W/sr),
    irradiance falls off as I cos / d^2; ambient float32[3] radiance of a uniform environment
    (a Lambert surface reflects albedo * ambient). Ld and Lp may be 0."""

    dir_to_light: Array
    dir_irradiance: Array
    point_position: Array
    point_intensity: Array
    ambient: Array


def make_lights(directional=(), point=(), ambient=(0.0, 0.0, 0.0)) -> Lights:
    """directional: iterable of (to_light[3], irradiance[3]); point: of (position, intensity).
    Scalars are broadcast to RGB."""
    rgb = lambda v: np.broadcast_to(np.asarray(v, np.float64), (3,))  # noqa: E731
    d = np.zeros((0, 3)), np.zeros((0, 3))
    if directional:
        dirs = np.array([np.asarray(t, np.float64) for t, _ in directional]).reshape(-1, 3)
        norms = np.linalg.norm(dirs, axis=1, keepdims=True)
        if np.any(norms == 0) or not np.all(np.isfinite(dirs)):
            raise ValueError("make_lights: a directional light has a zero or non-finite direction")
        d = dirs / norms, np.array([rgb(e) for _, e in directional])
    p = np.zeros((0, 3)), np.zeros((0, 3))
    if point:
        p = (np.array([np.asarray(x, np.float64) for x, _ in point]).reshape(-1, 3),
             np.array([rgb(i) for _, i in point]))
    f = lambda a: jnp.asarray(np.asarray(a, np.float32))  # noqa: E731
    return Lights(f(d[0]), f(d[1]), f(p[0]), f(p[1]), f(rgb(ambient)))
