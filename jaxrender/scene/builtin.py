"""Built-in procedural scenes, each made to stress one thing; no downloads, sizes parametric.

Every builder takes keyword size parameters only and returns a Scene with a default camera.
Defaults are small enough for a 2-core CPU; docstrings give the large settings.
"""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np

from jaxrender.scene.animation import ObjectMotion
from jaxrender.scene.camera import look_at
from jaxrender.scene.glass import glass
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import MeshPart, box, grid_plane, trs_matrix, uv_sphere
from jaxrender.scene.scene import Scene, build_scene

_SUN = ((0.4, 0.8, 0.45), 2.5)


# ---------------------------------------------------------------- procedural texture images

def checker_image(n=256, squares=8, a=(0.8, 0.8, 0.8), b=(0.2, 0.2, 0.25)) -> np.ndarray:
    i = (np.arange(n) * squares // n)
    mask = ((i[:, None] + i[None, :]) % 2 == 0)[..., None]
    rgb = np.where(mask, np.asarray(a), np.asarray(b))
    return np.concatenate([rgb, np.ones((n, n, 1))], -1)


def brick_image(n=256, rows=8) -> np.ndarray:
    y, x = np.mgrid[0:n, 0:n] / n * rows
    x = x + 0.5 * (np.floor(y) % 2)
    mortar = (np.minimum(y % 1, 1 - y % 1) < 0.06) | (np.minimum((x / 2) % 1, 1 - (x / 2) % 1) < 0.03)
    rgb = np.where(mortar[..., None], [0.55, 0.55, 0.5], [0.45, 0.15, 0.1])
    return np.concatenate([rgb, np.ones((n, n, 1))], -1)


def leaf_image(n=64) -> np.ndarray:
    """A leaf: green inside an ellipse (alpha 1), transparent outside (alpha 0)."""
    y, x = (np.mgrid[0:n, 0:n] + 0.5) / n * 2 - 1
    inside = (x / 0.55) ** 2 + (y / 0.95) ** 2 <= 1.0
    vein = np.abs(x) < 0.04
    rgb = np.where(vein[..., None], [0.35, 0.5, 0.15], [0.1, 0.45, 0.08])
    return np.concatenate([rgb, inside[..., None].astype(float)], -1)


def bump_normal_image(n=256, tiles=8, zero_texels=False) -> np.ndarray:
    """Tangent-space normal map of rounded tiles, encoded n * 0.5 + 0.5 (linear)."""
    t = (np.arange(n) + 0.5) / n * tiles % 1.0
    h1 = np.sin(np.pi * t)  # bump per tile
    dh_du = np.pi * np.cos(np.pi * t) * tiles * 0.02
    gx = np.broadcast_to(dh_du[None, :], (n, n)) * np.broadcast_to(h1[:, None], (n, n))
    gy = -np.broadcast_to(dh_du[:, None], (n, n)) * np.broadcast_to(h1[None, :], (n, n))
    nrm = np.stack([-gx, -gy, np.ones((n, n))], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    if zero_texels:
        nrm[: n // 8, : n // 8] = 0.0
    return np.concatenate([nrm * 0.5 + 0.5, np.ones((n, n, 1))], -1)


# ---------------------------------------------------------------- scenes

def stripes(*, plane_size: float = 400.0, subdivisions: int = 8,
            stripe_resolution: float = 2048.0) -> Scene:
    """A plane receding to the horizon under the 1-texel stripe shader (shader aliasing)."""
    plane = grid_plane((plane_size, plane_size), (subdivisions, subdivisions))
    plane = plane.transformed(trs_matrix(translate=(0, 0, -plane_size / 2 + 2)))
    mat = Material("stripes", albedo=(0.9, 0.9, 0.9), procedural="stripes",
                   stripe_resolution=stripe_resolution)
    cam = look_at((0, 1.0, 0.0), (0, 0.6, -10.0), fov_y_deg=50, near=0.05, far=2 * plane_size)
    return build_scene([plane], [mat], [], make_lights([_SUN], ambient=0.05), cam,
                       name="stripes", description=stripes.__doc__.splitlines()[0])


def spheres(*, rows: int = 3, cols: int = 4, lat: int = 12, lon: int = 24,
            spin_deg_per_s: float = 0.0) -> Scene:
    """A grid of Blinn-Phong spheres, exponents 1 to 4096 (specular aliasing).

    ``spin_deg_per_s``: each sphere spins about its own vertical axis (alternating direction),
    so the highlights stay while the surface, its uvs and its shading rate move under them."""
    n = rows * cols
    exps = np.geomspace(1.0, 4096.0, n)
    parts, mats = [], []
    for k in range(n):
        r, c = divmod(k, cols)
        s = uv_sphere(0.45, lat, lon, material=k)
        s = s.transformed(trs_matrix(translate=(c - (cols - 1) / 2, (rows - 1) / 2 - r + 1.0, 0)))
        if spin_deg_per_s:
            s.motion = ObjectMotion(spin_axis=(0.2, 1.0, 0.0),
                                    spin_deg_per_s=float(spin_deg_per_s) * (-1) ** k)
        parts.append(s)
        mats.append(Material(f"phong{exps[k]:.0f}", albedo=(0.5, 0.1, 0.1), specular=(0.5, 0.5, 0.5),
                             shininess=float(exps[k]), brdf="blinn_phong"))
    mats.append(Material("floor", albedo=(0.3, 0.3, 0.3)))
    floor = grid_plane((cols + 4, rows + 4), material=n).transformed(trs_matrix(translate=(0, 0.0, 0)))
    parts.append(floor)
    lights = make_lights([_SUN], [((2, 4, 3), 8.0), ((-3, 2, 2), (4.0, 4.0, 6.0))], ambient=0.03)
    cam = look_at((0, rows * 0.5 + 1, cols + 1.5), (0, (rows - 1) / 2 + 0.7, 0), fov_y_deg=45)
    return build_scene(parts, mats, [], lights, cam, name="spheres",
                       description=spheres.__doc__.splitlines()[0])


def spheres_spin(*, rows: int = 3, cols: int = 4, lat: int = 12, lon: int = 24,
                 spin_deg_per_s: float = 90.0) -> Scene:
    """The spheres, each spinning (rigid motion under fixed lights: motion vectors, TAA)."""
    scene = spheres(rows=rows, cols=cols, lat=lat, lon=lon, spin_deg_per_s=spin_deg_per_s)
    return dataclasses.replace(scene, name="spheres_spin",
                               description=spheres_spin.__doc__.splitlines()[0])


def foliage(*, n_cards: int = 200, card_size: float = 0.3, seed: int = 0,
            wind: float = 0.0) -> Scene:
    """Many small alpha-tested leaf cards over a ground plane (overdraw, tiny triangles).

    ``wind``: the leaves sway along +x by up to ``wind`` world units at 2.5 units above the
    ground, the displacement growing with the square of the height (the ground stays)."""
    rng = np.random.default_rng(seed)
    parts = [grid_plane((6, 6), material=1)]
    for k in range(n_cards):
        q = grid_plane((card_size, card_size))
        m = trs_matrix(translate=rng.uniform([-2, 0.2, -2], [2, 2.5, 2]),
                       rotate_deg=rng.uniform(0, 360, 3))
        q = q.transformed(m)
        if wind:
            q.motion = ObjectMotion(sway_amplitude=float(wind), sway_height=2.5, sway_base=0.0,
                                    sway_direction=(1.0, 0.0, 0.3), sway_frequency_hz=0.7)
        parts.append(q)
    mats = [Material("leaf", albedo=(1, 1, 1), texture=0, alpha_tested=True, alpha_cutoff=0.5),
            Material("ground", albedo=(0.35, 0.25, 0.15))]
    cam = look_at((0, 1.5, 5), (0, 1.2, 0), fov_y_deg=50)
    return build_scene(parts, mats, [leaf_image()], make_lights([_SUN], ambient=0.1), cam,
                       name="foliage", description=foliage.__doc__.splitlines()[0])


def foliage_wind(*, n_cards: int = 200, card_size: float = 0.3, seed: int = 0,
                 wind: float = 0.05) -> Scene:
    """The foliage swaying in the wind (vertex animation growing with height, as Decima's)."""
    scene = foliage(n_cards=n_cards, card_size=card_size, seed=seed, wind=wind)
    return dataclasses.replace(scene, name="foliage_wind",
                               description=foliage_wind.__doc__.splitlines()[0])


def grass(*, n_blades: int = 2000, segments: int = 4, blade_height: float = 0.6,
          blade_width: float = 0.04, patch: float = 4.0, seed: int = 0) -> Scene:
    """The foliage's ground and view under dense tall grass (many thin, tiny triangles).

    Each blade is a tapering vertical strip of ``segments`` quads (2 ``segments`` triangles),
    bent and turned at random, one object each: the blades are instances of one mesh (one
    instanced batch of the visibility buffer's micro batches). The talk's tall-grass case, at
    1080p: ``n_blades = 30000`` (240k triangles)."""
    rng = np.random.default_rng(seed)
    k = int(segments)
    t = np.linspace(0.0, 1.0, k + 1)
    half = 0.5 * blade_width * (1.0 - 0.85 * t)  # tapering towards the tip
    local = np.stack([np.concatenate([-half, half]), np.tile(t, 2) * blade_height,
                      np.zeros(2 * (k + 1))], 1)  # left column then right column
    uvs = np.stack([np.repeat([0.0, 1.0], k + 1), np.tile(t, 2)], 1)
    i = np.arange(k)
    faces = np.concatenate([np.stack([i, k + 1 + i, i + 1], 1),
                            np.stack([i + 1, k + 1 + i, k + 2 + i], 1)])
    parts = [grid_plane((6, 6), material=1)]
    for _ in range(int(n_blades)):
        bend = rng.uniform(0.0, 0.35)
        pos = local.copy()
        pos[:, 2] = bend * blade_height * np.tile(t, 2) ** 2  # leaning forward towards the tip
        height = rng.uniform(0.6, 1.0)
        m = trs_matrix(translate=(*rng.uniform(-patch / 2, patch / 2, 1), 0.0,
                                  *rng.uniform(-patch / 2, patch / 2, 1)),
                       rotate_deg=(0.0, rng.uniform(0, 360), 0.0), scale=(1.0, height, 1.0))
        nrm = np.tile([0.0, 0.0, 1.0], (len(pos), 1))
        tan = np.tile([1.0, 0.0, 0.0, 1.0], (len(pos), 1))
        parts.append(MeshPart(pos, faces, normals=nrm, uvs=uvs, tangents=tan,
                              material=0).transformed(m))
    mats = [Material("grass", albedo=(0.18, 0.42, 0.1)),
            Material("ground", albedo=(0.35, 0.25, 0.15))]
    cam = look_at((0, 1.5, 5), (0, 1.2, 0), fov_y_deg=50)
    return build_scene(parts, mats, [], make_lights([_SUN], ambient=0.1), cam,
                       name="grass", description=grass.__doc__.splitlines()[0])


def thin(*, n_wires: int = 24, fence_bars: int = 40, width: float = 0.004) -> Scene:
    """Wires and a fence narrower than a pixel in front of a wall (geometric aliasing)."""
    parts = [grid_plane((12, 6), material=1).transformed(trs_matrix((0, 3, -3), (90, 0, 0)))]
    for k in range(n_wires):  # sagging-free diagonal wires
        ang = -30 + 60 * k / max(n_wires - 1, 1)
        parts.append(box((10.0, width, width)).transformed(
            trs_matrix((0, 2.5 + 0.02 * k, -1.0 + 0.02 * k), (0, 0, ang * 0.1 + 2 * (k % 3)))))
    for k in range(fence_bars):
        x = -4 + 8 * k / max(fence_bars - 1, 1)
        parts.append(box((width, 2.0, width)).transformed(trs_matrix((x, 1.0, 0.5))))
    parts.append(box((8.0, width, width)).transformed(trs_matrix((0, 1.9, 0.5))))
    parts.append(grid_plane((12, 8), material=1))
    mats = [Material("wire", albedo=(0.05, 0.05, 0.05), specular=(0.6, 0.6, 0.6), shininess=64,
                     brdf="blinn_phong"),
            Material("wall", albedo=(0.8, 0.8, 0.75))]
    cam = look_at((0, 1.6, 7), (0, 1.6, 0), fov_y_deg=55)
    return build_scene(parts, mats, [], make_lights([_SUN], ambient=0.1), cam, name="thin",
                       description=thin.__doc__.splitlines()[0])


def terrain(*, res: int = 64, size: float = 40.0, texture_size: int = 128) -> Scene:
    """A continuous heightfield, dense near the centre and coarse at the rim (varying density)."""
    t = np.linspace(-1, 1, res + 1)
    t = np.sign(t) * np.abs(t) ** 2  # denser near 0
    gx, gz = np.meshgrid(t * size / 2, t * size / 2, indexing="xy")
    h = (1.5 * np.sin(gx * 0.3) * np.cos(gz * 0.25) + 0.5 * np.sin(gx * 1.3 + gz * 0.7))
    pos = np.stack([gx.ravel(), h.ravel(), gz.ravel()], 1)
    uvs = np.stack([gx.ravel() / 4, -gz.ravel() / 4], 1)
    i = np.arange(res)[:, None] * (res + 1) + np.arange(res)[None, :]
    a, b, c, d = i, i + 1, i + res + 1, i + res + 2
    faces = np.concatenate([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], 0).reshape(-1, 3)
    tex = checker_image(texture_size, 8, (0.25, 0.45, 0.15), (0.35, 0.3, 0.2))
    mats = [Material("ground", albedo=(1, 1, 1), texture=0, roughness=0.8, specular=(0.04,) * 3,
                     brdf="ggx")]
    cam = look_at((0, 6, size / 2), (0, 0, 0), fov_y_deg=55, far=200)
    return build_scene([MeshPart(pos, faces, uvs=uvs)], mats, [tex], make_lights([_SUN], ambient=0.1),
                       cam, name="terrain", description=terrain.__doc__.splitlines()[0])


def sliver(*, n_slivers: int = 64, n_degenerate: int = 16) -> Scene:
    """A fan of extreme slivers plus degenerate (zero-area) triangles on a wall."""
    ang = np.linspace(0, np.pi / 6, n_slivers + 1) ** 3 * 30  # very uneven, some tiny angles
    rim = np.stack([3 * np.cos(ang), 3 * np.sin(ang) - 1.2, np.zeros_like(ang)], 1)
    pos = np.concatenate([[[-1.5, -1.2, 0]], rim - [1.5, 0, 0]], 0)
    faces = np.stack([np.zeros(n_slivers, int), np.arange(1, n_slivers + 1),
                      np.arange(2, n_slivers + 2)], 1)
    base = len(pos)
    deg_p, deg_f = [], []
    for k in range(n_degenerate):  # collinear and repeated-vertex triangles
        p0 = np.array([0.5 + 0.1 * k, -1.0 + 0.12 * k, 0.0])
        deg_p += [p0, p0 + [0.3, 0.1, 0], p0 + [0.6, 0.2, 0] if k % 2 else p0]
        deg_f.append(base + 3 * k + np.arange(3))
    pos = np.concatenate([pos, np.array(deg_p).reshape(-1, 3)])
    faces = np.concatenate([faces, np.array(deg_f).reshape(-1, 3)])
    uvs = pos[:, :2] * 0.25
    nrm = np.tile([0.0, 0.0, 1.0], (len(pos), 1))
    mats = [Material("sliver", albedo=(0.7, 0.7, 0.2), specular=(0.3,) * 3, shininess=32,
                     brdf="blinn_phong")]
    cam = look_at((0, 0, 4), (0, 0, 0), fov_y_deg=60)
    return build_scene([MeshPart(pos, faces, nrm, uvs)], mats, [],
                       make_lights([((0.2, 0.3, 1.0), 2.0)], ambient=0.05), cam,
                       name="sliver", description=sliver.__doc__.splitlines()[0])


def room(*, texture_size: int = 128, sphere_detail: int = 16) -> Scene:
    """An open-top room: textured walls, a normal-mapped floor, GGX and emissive objects, shadows."""
    w, h, d = 6.0, 3.0, 6.0
    walls = [
        (grid_plane((w, d), uv_scale=(3, 3), material=1), trs_matrix((0, 0, 0))),  # floor
        (grid_plane((w, h), uv_scale=(3, 1.5), material=0), trs_matrix((0, h / 2, -d / 2), (90, 0, 0))),
        (grid_plane((d, h), uv_scale=(3, 1.5), material=0), trs_matrix((-w / 2, h / 2, 0), (90, 90, 0))),
        (grid_plane((d, h), uv_scale=(3, 1.5), material=0), trs_matrix((w / 2, h / 2, 0), (90, -90, 0))),
    ]
    parts = [p.transformed(m) for p, m in walls]
    parts.append(uv_sphere(0.6, sphere_detail, 2 * sphere_detail, material=2).transformed(
        trs_matrix((-1.2, 0.6, -0.5))))
    parts.append(box((1.0, 1.4, 1.0), material=3).transformed(trs_matrix((1.3, 0.7, -1.2), (0, 30, 0))))
    parts.append(box((0.8, 0.05, 0.4), material=4).transformed(trs_matrix((0, 2.6, -2.9))))
    mats = [
        Material("brick", albedo=(1, 1, 1), texture=0),
        Material("tiles", albedo=(1, 1, 1), texture=1, normal_map=2, specular=(0.5,) * 3,
                 shininess=200, brdf="blinn_phong"),
        Material("metal", albedo=(0.2, 0.2, 0.2), specular=(0.9, 0.7, 0.4), roughness=0.3, brdf="ggx"),
        Material("plastic", albedo=(0.1, 0.3, 0.6), specular=(0.04,) * 3, roughness=0.5, brdf="ggx"),
        Material("lamp", albedo=(0.1, 0.1, 0.1), emissive=(4.0, 3.6, 3.0)),
    ]
    texs = [brick_image(texture_size), checker_image(texture_size, 8),
            bump_normal_image(texture_size, 8)]
    lights = make_lights([((0.3, 0.9, 0.5), 2.0)], [((0, 2.4, -2.0), (3.0, 2.7, 2.2)),
                                                    ((2.0, 1.5, 1.0), 1.5)], ambient=0.05)
    cam = look_at((0.5, 1.6, 2.9), (-0.3, 0.8, -1.5), fov_y_deg=65)
    return build_scene(parts, mats, texs, lights, cam, name="room", shadows=True,
                       description=room.__doc__.splitlines()[0])


def many_small(*, n_triangles: int = 20_000, size: float = 4.0, point_lights: int = 0) -> Scene:
    """A dune surface of n_triangles tiny triangles for scale (large: n_triangles=1_048_576).

    At the large setting the triangles are sub-pixel at 1920x1080 from the default camera.
    ``point_lights`` adds that many coloured point lights in a ring above the dunes (the
    performance studies' target scene is n_triangles=100000, point_lights=4)."""
    q = max(int(np.sqrt(n_triangles / 2)), 1)
    nx, nz = q, max(int(np.ceil(n_triangles / (2 * q))), 1)
    plane = grid_plane((size, size * nz / nx), (nx, nz))
    x, z = plane.positions[:, 0], plane.positions[:, 2]
    plane.positions[:, 1] = 0.15 * np.sin(x * 6) * np.cos(z * 5)
    plane.normals = None  # recomputed from the displaced surface
    mats = [Material("sand", albedo=(0.8, 0.7, 0.5), specular=(0.2,) * 3, shininess=16,
                     brdf="blinn_phong")]
    cam = look_at((0, 2.5, size * 0.9), (0, 0, 0), fov_y_deg=50)
    ring = [((0.35 * size * np.cos(a), 0.6, 0.35 * size * np.sin(a)),
             (1.0 + 0.5 * np.cos(a), 1.0, 1.0 + 0.5 * np.sin(a)))
            for a in 2 * np.pi * np.arange(int(point_lights)) / max(int(point_lights), 1)]
    return build_scene([plane], mats, [], make_lights([_SUN], ring, ambient=0.1), cam,
                       name="many_small", description=many_small.__doc__.splitlines()[0])


BUILTINS = {f.__name__: f for f in (stripes, spheres, foliage, thin, terrain, sliver, room, many_small,
                                     foliage_wind, spheres_spin, grass, glass)}


def list_builtin_scenes() -> list[tuple[str, str]]:
    return [(n, f.__doc__.strip().splitlines()[0]) for n, f in BUILTINS.items()]


def builtin_scene(name: str, **size_params) -> Scene:
    fn = BUILTINS[name]
    allowed = [p for p in inspect.signature(fn).parameters]
    unknown = sorted(set(size_params) - set(allowed))
    if unknown:
        raise TypeError(f"built-in scene {name!r} has no parameter {unknown[0]!r}; "
                        f"its parameters are: {', '.join(allowed)}")
    return fn(**size_params)
