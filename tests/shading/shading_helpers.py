"""Test helpers: hand-made surface points and one raster shape shared by every render test
(the rasterizer compiles per (V, T, width, height); padding to one shape compiles it once)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.scene import Material, MeshPart, build_scene, look_at, make_lights
from jaxrender.scene.mesh import grid_plane
from jaxrender.types import SurfacePoints

PAD_V = PAD_T = 8192
RES = 32


def points(n_pts: int, *, position=(0, 0, 0), normal=(0, 1, 0), view=(0, 1, 0), uv=(0.5, 0.5),
           duv=(0.0, 0.0), material=0, tangent=(1, 0, 0, 1)) -> SurfacePoints:
    """N identical-shape points; every argument broadcasts to [N, k]."""
    f = lambda v, k: jnp.asarray(np.broadcast_to(np.asarray(v, np.float32), (n_pts, k)))  # noqa: E731
    nrm = np.broadcast_to(np.asarray(normal, np.float64), (n_pts, 3))
    nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    vw = np.broadcast_to(np.asarray(view, np.float64), (n_pts, 3))
    vw = vw / np.linalg.norm(vw, axis=1, keepdims=True)
    duv = np.broadcast_to(np.asarray(duv, np.float32), (n_pts, 2))
    return SurfacePoints(
        position=f(position, 3), normal=f(nrm, 3), shading_normal=f(nrm, 3),
        tangent=f(tangent, 4), uv=f(uv, 2), duv_dx=jnp.asarray(duv),
        duv_dy=jnp.asarray(np.stack([-duv[:, 1], duv[:, 0]], 1)),
        view=f(vw, 3), material=jnp.asarray(np.broadcast_to(np.int32(material), (n_pts,))),
        tri_id=jnp.zeros((n_pts,), jnp.int32), valid=jnp.ones((n_pts,), bool),
    )


def plane_scene(materials=None, textures=(), directional=(), point=(), ambient=0.0, **kw):
    mats = materials or [Material("m", albedo=(0.5, 0.5, 0.5))]
    cam = look_at((0, 2, 2), (0, 0, 0))
    return build_scene([grid_plane((4, 4))], mats, list(textures),
                       make_lights(directional, point, ambient), cam, name="plane", **kw)


def padding_part(n_vertices: int, n_faces: int) -> MeshPart:
    """Degenerate triangles (all three corners on one vertex): never covered."""
    return MeshPart(np.zeros((max(n_vertices, 1), 3)), np.zeros((n_faces, 3), np.int64),
                    normals=np.tile([0.0, 1.0, 0.0], (max(n_vertices, 1), 1)))


def raster(positions, faces, camera, width=RES, height=RES):
    """The shared rasterizer on positions/faces padded to (PAD_V, PAD_T)."""
    from jaxrender.raster import rasterize

    v, t = positions.shape[0], faces.shape[0]
    assert v <= PAD_V and t <= PAD_T, (v, t)
    pos = jnp.concatenate([positions, jnp.zeros((PAD_V - v, 3), jnp.float32)])
    fac = jnp.concatenate([faces, jnp.zeros((PAD_T - t, 3), jnp.int32)])
    return rasterize(pos, fac, camera, width, height)


def flat(vis):
    return (vis.tri_id.reshape(-1), vis.bary.reshape(-1, 3), vis.dbary_dx.reshape(-1, 3),
            vis.dbary_dy.reshape(-1, 3))
