"""NumPy mesh parts (before flattening into a Scene): primitives, transforms, normals, tangents;
and bare (vertices, faces) meshes for rasterizer tests and benchmarks: a 2D grid with an exact
triangle count, a heightfield terrain and a closed sphere."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np


@dataclass
class MeshPart:
    """One mesh (or instance) in world or object space. material: one index or int[T] per face."""

    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None = None
    uvs: np.ndarray | None = None
    tangents: np.ndarray | None = None
    material: int | np.ndarray = 0
    velocity: np.ndarray | None = None  # per-vertex world displacement per frame ([3] or [V,3])
    motion: object = None  # an animation.ObjectMotion, or None for a part that does not move
    name: str = ""
    extras: dict = field(default_factory=dict)

    def transformed(self, matrix) -> "MeshPart":
        """The part under a 4x4 affine transform (normals by the inverse transpose)."""
        m = np.asarray(matrix, np.float64)
        lin, t = m[:3, :3], m[:3, 3]
        pos = self.positions @ lin.T + t
        nrm = None if self.normals is None else _normalize(self.normals @ np.linalg.inv(lin))
        tan = None
        if self.tangents is not None:
            tan = np.concatenate([_normalize(self.tangents[:, :3] @ lin.T), self.tangents[:, 3:]], 1)
        faces = self.faces if np.linalg.det(lin) > 0 else self.faces[:, ::-1]
        return replace(self, positions=pos, normals=nrm, tangents=tan, faces=faces)


def _normalize(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 0, v / np.where(n > 0, n, 1.0), 0.0)


def trs_matrix(translate=(0, 0, 0), rotate_deg=(0, 0, 0), scale=1.0) -> np.ndarray:
    """4x4 = T * Rz * Ry * Rx * S (rotations in degrees about the world axes, X applied first)."""
    rx, ry, rz = np.deg2rad(np.asarray(rotate_deg, np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    r_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    r_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    r_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = r_z @ r_y @ r_x @ np.diag(np.broadcast_to(np.asarray(scale, np.float64), (3,)))
    m[:3, 3] = translate
    return m


def face_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    p = positions[faces]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])  # area-weighted, not normalised


def vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    fn = face_normals(positions, faces)
    acc = np.zeros_like(positions, dtype=np.float64)
    for k in range(3):
        for c in range(3):
            acc[:, c] += np.bincount(faces[:, k], fn[:, c], minlength=len(positions))
    return _normalize(acc)


def vertex_tangents(positions, normals, uvs, faces) -> np.ndarray:
    """Per-vertex tangents float[V,4] (xyz unit, w = bitangent sign) from the UV layout
    (Lengyel's method). Vertices without a usable UV gradient get any tangent orthogonal to n."""
    p, t = positions[faces], uvs[faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    r = np.where(np.abs(det) > 1e-20, 1.0 / np.where(det == 0, 1.0, det), 0.0)[:, None]
    ft = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r
    fb = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r
    tan, bit = np.zeros_like(positions), np.zeros_like(positions)
    for k in range(3):
        for c in range(3):
            tan[:, c] += np.bincount(faces[:, k], ft[:, c], minlength=len(positions))
            bit[:, c] += np.bincount(faces[:, k], fb[:, c], minlength=len(positions))
    n = normals
    tan = tan - n * np.sum(n * tan, axis=1, keepdims=True)
    bad = np.linalg.norm(tan, axis=1) < 1e-12
    if np.any(bad):  # any vector orthogonal to n
        helper = np.where(np.abs(n[bad, 0:1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        tan[bad] = np.cross(n[bad], helper)
    tan = _normalize(tan)
    w = np.where(np.sum(np.cross(n, tan) * bit, axis=1) < 0.0, -1.0, 1.0)
    return np.concatenate([tan, w[:, None]], axis=1)


def complete(part: MeshPart) -> MeshPart:
    """Fill in missing normals (area-weighted), uvs (zeros) and tangents."""
    pos = np.asarray(part.positions, np.float64)
    faces = np.asarray(part.faces, np.int64).reshape(-1, 3)
    nrm = vertex_normals(pos, faces) if part.normals is None else np.asarray(part.normals, np.float64)
    uvs = np.zeros((len(pos), 2)) if part.uvs is None else np.asarray(part.uvs, np.float64)
    tan = part.tangents if part.tangents is not None else vertex_tangents(pos, nrm, uvs, faces)
    return replace(part, positions=pos, faces=faces, normals=nrm, uvs=uvs,
                   tangents=np.asarray(tan, np.float64))


# ---------------------------------------------------------------- primitives (object space)

def grid_plane(size=(1.0, 1.0), res=(1, 1), uv_scale=(1.0, 1.0), material=0) -> MeshPart:
    """A plane in XZ (normal +Y), centred at the origin; uv = (x, -z) mapped to [0, uv_scale]."""
    nx, nz = res
    xs = np.linspace(-0.5, 0.5, nx + 1) * size[0]
    zs = np.linspace(-0.5, 0.5, nz + 1) * size[1]
    gx, gz = np.meshgrid(xs, zs, indexing="xy")
    pos = np.stack([gx.ravel(), np.zeros(gx.size), gz.ravel()], 1)
    uvs = np.stack([(gx.ravel() / size[0] + 0.5) * uv_scale[0],
                    (0.5 - gz.ravel() / size[1]) * uv_scale[1]], 1)
    i = np.arange(nz)[:, None] * (nx + 1) + np.arange(nx)[None, :]
    a, b, c, d = i, i + 1, i + nx + 1, i + nx + 2
    faces = np.concatenate([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], 0).reshape(-1, 3)
    nrm = np.tile([0.0, 1.0, 0.0], (len(pos), 1))
    return MeshPart(pos, faces, nrm, uvs, material=material)


def uv_sphere(radius=1.0, n_lat=16, n_lon=32, material=0) -> MeshPart:
    th = np.linspace(0, np.pi, n_lat + 1)
    ph = np.linspace(0, 2 * np.pi, n_lon + 1)
    t, p = np.meshgrid(th, ph, indexing="ij")
    nrm = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    uvs = np.stack([p / (2 * np.pi), 1 - t / np.pi], -1).reshape(-1, 2)
    i = np.arange(n_lat)[:, None] * (n_lon + 1) + np.arange(n_lon)[None, :]
    a, b, c, d = i, i + 1, i + n_lon + 1, i + n_lon + 2
    faces = np.concatenate([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], 0).reshape(-1, 3)
    return MeshPart(nrm * radius, faces, nrm, uvs, material=material)


def box(size=(1.0, 1.0, 1.0), material=0) -> MeshPart:
    """An axis-aligned box centred at the origin, 24 vertices (flat normals, per-face uvs)."""
    parts = []
    for axis, sign in [(0, 1), (0, -1), (1, 1), (1, -1), (2, 1), (2, -1)]:
        q = grid_plane((1.0, 1.0))
        # rotate +Y onto (axis, sign)
        rot = {(1, 1): (0, 0, 0), (1, -1): (180, 0, 0), (0, 1): (0, 0, -90), (0, -1): (0, 0, 90),
               (2, 1): (90, 0, 0), (2, -1): (-90, 0, 0)}[(axis, sign)]
        m = trs_matrix(translate=np.eye(3)[axis] * 0.5 * sign, rotate_deg=rot)
        parts.append(q.transformed(m))
    merged = merge(parts, material=material)
    merged.positions = merged.positions * np.asarray(size, np.float64)
    return merged


def merge(parts: list[MeshPart], material=0) -> MeshPart:
    offs = np.cumsum([0] + [len(p.positions) for p in parts])
    cat = lambda k: np.concatenate([getattr(p, k) for p in parts], 0)  # noqa: E731
    return MeshPart(cat("positions"), np.concatenate([p.faces + o for p, o in zip(parts, offs)]),
                    cat("normals"), cat("uvs"), material=material)


# ---------------------------------------------------------------- bare (vertices, faces) meshes


def grid_mesh(nx: int, ny: int, *, extent=(-1.0, 1.0, -1.0, 1.0), jitter=0.0, seed=0):
    """A (nx x ny)-cell 2D grid of 2*nx*ny triangles sharing edges, as (vertices[V,2], faces[T,3]).

    ``jitter`` moves interior vertices by up to that fraction of a cell (shared edges stay shared).
    """
    x0, x1, y0, y1 = extent
    xs, ys = np.meshgrid(np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1))
    verts = np.stack([xs, ys], -1).reshape(-1, 2)
    if jitter:
        rng = np.random.default_rng(seed)
        cell = np.array([(x1 - x0) / nx, (y1 - y0) / ny])
        interior = np.zeros((ny + 1, nx + 1), bool)
        interior[1:-1, 1:-1] = True
        d = rng.uniform(-jitter, jitter, verts.shape) * cell
        verts = verts + d * interior.reshape(-1, 1)
    i = np.arange(ny)[:, None] * (nx + 1) + np.arange(nx)[None, :]
    a, b, c, d = i, i + 1, i + nx + 1, i + nx + 2
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)], 0).reshape(-1, 3)
    return verts, faces.astype(np.int32)


def terrain_mesh(n_tris: int, *, seed=0):
    """A heightfield of about ``n_tris`` triangles in world space (x, z in [-50, 50])."""
    n = max(1, int(round(np.sqrt(n_tris / 2))))
    v2, faces = grid_mesh(n, n, extent=(-50, 50, -50, 50), jitter=0.3, seed=seed)
    x, z = v2[:, 0], v2[:, 1]
    rng = np.random.default_rng(seed)
    k = rng.uniform(0.05, 0.3, (4, 2))
    h = sum(np.sin(k[i, 0] * x + i) * np.cos(k[i, 1] * z - i) for i in range(4)) * 2.0
    return np.stack([x, h, z], -1).astype(np.float32), faces


def closed_uv_sphere(n_lat: int, n_lon: int, radius=1.0, center=(0.0, 0.0, 0.0)):
    """A closed, consistently wound UV sphere (poles shared, seam shared) as (vertices[V, 3],
    faces[T, 3]): watertight, unlike ``uv_sphere``, whose seam is split for its uvs."""
    lat = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    ring = np.stack(
        [np.sin(lat)[:, None] * np.cos(lon), np.cos(lat)[:, None] + 0 * lon,
         np.sin(lat)[:, None] * np.sin(lon)], -1
    ).reshape(-1, 3)
    verts = np.concatenate([[[0, 1, 0]], ring, [[0, -1, 0]]]) * radius + np.asarray(center)
    faces = []
    top, bottom = 0, len(verts) - 1
    idx = lambda r, c: 1 + r * n_lon + (c % n_lon)  # noqa: E731
    for c in range(n_lon):
        faces.append([top, idx(0, c + 1), idx(0, c)])
        faces.append([bottom, idx(n_lat - 2, c), idx(n_lat - 2, c + 1)])
        for r in range(n_lat - 2):
            faces.append([idx(r, c), idx(r, c + 1), idx(r + 1, c + 1)])
            faces.append([idx(r, c), idx(r + 1, c + 1), idx(r + 1, c)])
    return verts.astype(np.float32), np.asarray(faces, np.int32)
