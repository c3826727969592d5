"""Scene animation on one clock: frame ``t`` of every sequence is the time ``t / fps`` seconds,
shared by the camera path (one camera per frame) and the scene's motion.

A scene declares its motion per object (``ObjectMotion``, host-side): rigid spin about an axis
through a pivot, constant velocity, an orbit of the pivot about a centre (the object keeps its
orientation), and wind sway for foliage (a displacement along the wind that grows with the
vertex's height above a base, ``amplitude * (height / sway_height) ** sway_exponent``, phased
along the wind so that neighbouring plants lag each other, as shipped foliage shaders do).

``build_animation`` packs the declarations into the traced ``Animation`` the Scene carries (None
for a static scene, which then compiles none of it). ``pose(scene, t)`` is the scene at frame
``t``: the positions, normals and tangents recomputed from the rest pose, so ``pose`` of a posed
scene at another frame is that frame's pose (the motion vectors pose frame t-1 this way).
Swaying bends a surface, so its normals and tangents follow the deformation's Jacobian
``J = R + u g^T`` (``u`` the wind direction, ``g`` the gradient of the sway displacement's size
over the rest position): tangents by ``J``, normals by its cofactor (``J^-T`` up to scale).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxrender.types import Array, pytree_dataclass, static_field

DEFAULT_FPS = 60.0


@dataclass(frozen=True)
class ObjectMotion:
    """The motion of one object (mesh part). Angles in degrees per second, lengths in world
    units, velocities per second. ``pivot`` None: the object's bounding-box centre;
    ``sway_base`` None: the object's lowest point."""

    spin_axis: tuple = (0.0, 1.0, 0.0)
    spin_deg_per_s: float = 0.0
    pivot: tuple | None = None
    velocity: tuple = (0.0, 0.0, 0.0)
    orbit_center: tuple = (0.0, 0.0, 0.0)
    orbit_axis: tuple = (0.0, 1.0, 0.0)
    orbit_deg_per_s: float = 0.0
    sway_amplitude: float = 0.0
    sway_direction: tuple = (1.0, 0.0, 0.0)
    sway_frequency_hz: float = 0.5
    sway_wavelength: float = 4.0
    sway_height: float = 1.0
    sway_exponent: float = 2.0
    sway_base: float | None = None

    def __post_init__(self):
        for key in ("spin_axis", "orbit_axis", "sway_direction"):
            v = np.asarray(getattr(self, key), np.float64)
            if v.shape != (3,) or not np.all(np.isfinite(v)) or np.linalg.norm(v) == 0.0:
                raise ValueError(f"{key} must be a non-zero 3-vector, got {getattr(self, key)}")
        for key in ("sway_height", "sway_wavelength"):
            if not float(getattr(self, key)) > 0.0:
                raise ValueError(f"{key} must be > 0, got {getattr(self, key)}")
        if float(self.sway_exponent) < 0.0:
            raise ValueError(f"sway_exponent must be >= 0, got {self.sway_exponent}")
        if float(self.sway_frequency_hz) < 0.0:
            raise ValueError(f"sway_frequency_hz must be >= 0, got {self.sway_frequency_hz}")

    @property
    def rigid(self) -> bool:
        return bool(self.spin_deg_per_s or self.orbit_deg_per_s or np.any(self.velocity))

    @property
    def sways(self) -> bool:
        return bool(self.sway_amplitude)


MOTION_KEYS = tuple(f.name for f in dataclasses.fields(ObjectMotion))


@pytree_dataclass
class Animation:
    """The traced motion of a scene with O objects and V vertices.

    vertex_object int32[V]; rest_positions, rest_normals float32[V, 3]; rest_tangents
    float32[V, 4]; spin_axis float32[O, 3] (unit); spin_rate float32[O] (rad/s); pivot
    float32[O, 3]; velocity float32[O, 3]; orbit_center, orbit_axis float32[O, 3]; orbit_rate
    float32[O] (rad/s); sway_offset float32[V, 3] (peak displacement); sway_phase float32[V]
    (rad); sway_omega float32[V] (rad/s); sway_direction float32[V, 3] (unit); sway_slope
    float32[V] (the peak displacement's derivative along y); sway_wave float32[V] (peak
    displacement x wavenumber: its phase's derivative along the wind). Static: fps, and which
    kinds are present (a scene that only sways compiles no rigid transform, and the other way
    round)."""

    vertex_object: Array
    rest_positions: Array
    rest_normals: Array
    rest_tangents: Array
    spin_axis: Array
    spin_rate: Array
    pivot: Array
    velocity: Array
    orbit_center: Array
    orbit_axis: Array
    orbit_rate: Array
    sway_offset: Array
    sway_phase: Array
    sway_omega: Array
    sway_direction: Array
    sway_slope: Array
    sway_wave: Array
    fps: float = static_field(default=DEFAULT_FPS)
    rigid: bool = static_field(default=False)
    sways: bool = static_field(default=False)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


def build_animation(motions: list, positions: np.ndarray, normals: np.ndarray,
                    tangents: np.ndarray, vertex_object: np.ndarray,
                    fps: float = DEFAULT_FPS) -> Animation | None:
    """The Animation of objects ``motions[o]`` (an ObjectMotion or None each), or None when
    nothing moves."""
    if not float(fps) > 0.0:
        raise ValueError(f"fps must be > 0, got {fps}")
    motions = [m or ObjectMotion() for m in motions]
    rigid = any(m.rigid for m in motions)
    sways = any(m.sways for m in motions)
    if not (rigid or sways):
        return None
    pos = np.asarray(positions, np.float64)
    obj = np.asarray(vertex_object, np.int64)
    pivot, weight, height = _pivots_and_sway(motions, pos, obj)
    per_v = lambda f: np.asarray([f(m) for m in motions], np.float64)[obj]  # noqa: E731
    direction = np.stack([_unit(m.sway_direction) for m in motions])[obj]
    amplitude, exponent = per_v(lambda m: m.sway_amplitude), per_v(lambda m: m.sway_exponent)
    # d weight / dy: zero below the base (the height is clamped there) and for exponent 0.
    lifted = (height > 0.0) & (exponent > 0.0)
    slope = np.where(lifted, amplitude * exponent * np.where(lifted, height, 1.0) ** (
        exponent - 1.0) / per_v(lambda m: m.sway_height), 0.0)
    along = np.sum(pos * direction, axis=-1)
    wavenumber = 2 * np.pi / per_v(lambda m: m.sway_wavelength)
    phase = wavenumber * along
    f32 = lambda a: jnp.asarray(np.asarray(a, np.float32))  # noqa: E731
    rad = np.deg2rad
    return Animation(
        vertex_object=jnp.asarray(obj.astype(np.int32)), rest_positions=f32(pos),
        rest_normals=f32(normals), rest_tangents=f32(tangents),
        spin_axis=f32([_unit(m.spin_axis) for m in motions]),
        spin_rate=f32([rad(m.spin_deg_per_s) for m in motions]), pivot=f32(pivot),
        velocity=f32([m.velocity for m in motions]),
        orbit_center=f32([m.orbit_center for m in motions]),
        orbit_axis=f32([_unit(m.orbit_axis) for m in motions]),
        orbit_rate=f32([rad(m.orbit_deg_per_s) for m in motions]),
        sway_offset=f32(weight[:, None] * direction), sway_phase=f32(phase),
        sway_omega=f32(2 * np.pi * per_v(lambda m: m.sway_frequency_hz)),
        sway_direction=f32(direction), sway_slope=f32(slope), sway_wave=f32(weight * wavenumber),
        fps=float(fps), rigid=rigid, sways=sways)


def _pivots_and_sway(motions: list, pos: np.ndarray, obj: np.ndarray):
    """(pivot [O, 3], peak sway displacement [V], height over the sway base in sway_height
    units [V]) of ObjectMotions ``motions`` over rest positions ``pos``."""
    pivot = np.zeros((len(motions), 3))
    base = np.zeros(len(motions))
    for o, m in enumerate(motions):
        p = pos[obj == o]
        lo, hi = (p.min(0), p.max(0)) if len(p) else (np.zeros(3), np.zeros(3))
        pivot[o] = 0.5 * (lo + hi) if m.pivot is None else np.asarray(m.pivot, np.float64)
        base[o] = lo[1] if m.sway_base is None else float(m.sway_base)
    per_v = lambda f: np.asarray([f(m) for m in motions], np.float64)[obj]  # noqa: E731
    height = np.maximum(pos[:, 1] - base[obj], 0.0) / per_v(lambda m: m.sway_height)
    weight = per_v(lambda m: m.sway_amplitude) * height ** per_v(lambda m: m.sway_exponent)
    return pivot, weight, height


def reach(anim: Animation) -> np.ndarray:
    """float64[2, 3]: a box that holds every vertex of ``anim`` at every time under spin, orbit
    and sway (the rest pose included), for the shadow map's light box. Conservative: a
    spinning or orbiting object stays in the sphere about its orbit centre (or its pivot) of
    radius the pivot's distance to it plus the object's farthest vertex from the pivot and its
    largest sway, and a swaying vertex within its peak displacement. A constant velocity has no
    bound: its object is boxed at rest, so its shadows end where it leaves the box."""
    pos = np.asarray(anim.rest_positions, np.float64)
    obj = np.asarray(anim.vertex_object)
    pivot, centre = np.asarray(anim.pivot, np.float64), np.asarray(anim.orbit_center, np.float64)
    sway = np.linalg.norm(np.asarray(anim.sway_offset, np.float64), axis=-1)
    spins, orbits = np.asarray(anim.spin_rate) != 0, np.asarray(anim.orbit_rate) != 0
    lo, hi = (pos - sway[:, None]).min(0), (pos + sway[:, None]).max(0)
    for o in np.flatnonzero(spins | orbits):
        mine = obj == o
        if not mine.any():
            continue
        about = centre[o] if orbits[o] else pivot[o]
        radius = (np.linalg.norm(pivot[o] - about)
                  + np.linalg.norm(pos[mine] - pivot[o], axis=-1).max() + sway[mine].max())
        lo, hi = np.minimum(lo, about - radius), np.maximum(hi, about + radius)
    return np.stack([lo, hi])


def rotation_matrices(axis: Array, angle: Array) -> Array:
    """Rodrigues: float32[O, 3, 3] rotations by ``angle`` [O] about unit ``axis`` [O, 3]."""
    c, s = jnp.cos(angle)[:, None, None], jnp.sin(angle)[:, None, None]
    x, y, z = axis[:, 0], axis[:, 1], axis[:, 2]
    zero = jnp.zeros_like(x)
    k = jnp.stack([jnp.stack([zero, -z, y], -1), jnp.stack([z, zero, -x], -1),
                   jnp.stack([-y, x, zero], -1)], -2)
    kk = jnp.einsum("oij,ojk->oik", k, k, precision="highest")
    return jnp.eye(3, dtype=jnp.float32)[None] + s * k + (1.0 - c) * kk


def _apply(m: Array, v: Array) -> Array:
    """Per-row 3x3 products m [V, 3, 3] @ v [V, 3], elementwise (no reduced-precision unit)."""
    return jnp.sum(m * v[:, None, :], axis=-1)


def pose_arrays(anim: Animation, t) -> tuple[Array, Array, Array]:
    """(positions, normals, tangents) at frame ``t`` (a traced or Python number)."""
    seconds = jnp.asarray(t, jnp.float32) / jnp.float32(anim.fps)
    pos, nrm, tan = anim.rest_positions, anim.rest_normals, anim.rest_tangents
    r = None
    if anim.rigid:
        spin = rotation_matrices(anim.spin_axis, anim.spin_rate * seconds)
        orbit = rotation_matrices(anim.orbit_axis, anim.orbit_rate * seconds)
        rel = anim.pivot - anim.orbit_center
        moved_pivot = (anim.orbit_center + jnp.sum(orbit * rel[:, None, :], axis=-1)
                       + anim.velocity * seconds)
        o = anim.vertex_object
        r = spin[o]
        pos = _apply(r, pos - anim.pivot[o]) + moved_pivot[o]
        nrm = _apply(r, nrm)
        tan = jnp.concatenate([_apply(r, tan[:, :3]), tan[:, 3:]], axis=-1)
    if anim.sways:
        phase = anim.sway_omega * seconds + anim.sway_phase
        pos = pos + anim.sway_offset * jnp.sin(phase)[:, None]
        nrm, tan = _swayed_frames(anim, phase, r)
    return pos, nrm, tan


def _dot(a: Array, b: Array) -> Array:
    return jnp.sum(a * b, axis=-1, keepdims=True)


def _normalized(v: Array) -> Array:
    return v / jnp.maximum(jnp.sqrt(_dot(v, v)), 1e-20)


def _swayed_frames(anim: Animation, phase: Array, r: Array | None) -> tuple[Array, Array]:
    """Normals and tangents of the swayed (and, with ``r`` [V, 3, 3], rotated) surface.

    The position is ``x(p) = R (p - pivot) + moved + u w(p) sin(phase(p))``, so its Jacobian
    is ``J = R + u g^T`` with ``g = sin(phase) w'(p) + cos(phase) w(p) phase'(p)``; with
    ``u' = R^T u``, ``J = R (I + u' g^T)``: tangents go to ``R (t + u' (g . t))`` and normals,
    by the cofactor of ``I + u' g^T``, to ``R ((1 + g . u') n - g (u' . n))``."""
    up = jnp.asarray([[0.0, 1.0, 0.0]], jnp.float32)
    u = anim.sway_direction
    g = ((jnp.sin(phase) * anim.sway_slope)[:, None] * up
         + (jnp.cos(phase) * anim.sway_wave)[:, None] * u)
    n0, t0 = anim.rest_normals, anim.rest_tangents[:, :3]
    u_rest = u if r is None else _apply(jnp.swapaxes(r, -1, -2), u)
    nrm = (1.0 + _dot(g, u_rest)) * n0 - g * _dot(u_rest, n0)
    tan = t0 + u_rest * _dot(g, t0)
    if r is not None:
        nrm, tan = _apply(r, nrm), _apply(r, tan)
    return (_normalized(nrm),
            jnp.concatenate([_normalized(tan), anim.rest_tangents[:, 3:]], axis=-1))


def pose(scene, t):
    """The scene at frame ``t``; a static scene (no animation) is returned as it is."""
    if getattr(scene, "animation", None) is None:  # a scene of another kind (a test double)
        return scene
    pos, nrm, tan = pose_arrays(scene.animation, t)
    return dataclasses.replace(scene, positions=pos, normals=nrm, tangents=tan)


def positions_at(scene, t) -> Array:
    """World positions at frame ``t`` (the scene's own positions when it does not move)."""
    if getattr(scene, "animation", None) is None:  # a scene of another kind (a test double)
        return scene.positions
    return pose_arrays(scene.animation, t)[0]


__all__ = ["Animation", "DEFAULT_FPS", "MOTION_KEYS", "ObjectMotion", "build_animation",
           "pose", "pose_arrays", "positions_at", "reach", "rotation_matrices"]
