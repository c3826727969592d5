"""jaxrenderer 0.4.0 (PyPI, ``import renderer``) rendering depth only, for bench_peers.py."""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.bench.raster import terrain_camera
from jaxrender.timing import time_compiled


def jaxrenderer_available() -> str | None:
    try:
        with warnings.catch_warnings():  # its decorators warn once per function (jaxtyping)
            warnings.simplefilter("ignore")
            import renderer  # noqa: F401
            from renderer.shaders.depth import DepthShader  # noqa: F401
    except Exception as e:  # noqa: BLE001
        return f"jaxrenderer not importable ({type(e).__name__}: {e})"
    return None


def jaxrenderer_depth(verts, faces, width, height, repeats):
    """jaxrenderer's depth-only render of the benchmark terrain through the same camera.

    jaxrenderer always culls back faces (its default primitive chooser keeps front-facing
    fragments only, front = its determinant >= 0), and the terrain's winding is the other way
    round in its convention, so it gets the faces reversed: the same surface, facing it."""
    import renderer
    from renderer.shaders.depth import DepthExtraInput, DepthShader

    cam = terrain_camera()
    rot = np.asarray(cam.rotation, np.float64)
    eye = np.asarray(cam.eye, np.float64)
    view = np.eye(4)
    view[:3, :3] = rot
    view[:3, 3] = -rot @ eye
    proj = renderer.Camera.perspective_projection_matrix(
        float(np.rad2deg(float(cam.fov_y))), width / height, float(cam.near), float(cam.far))
    viewport = renderer.Camera.viewport_matrix(jnp.zeros(2, dtype=int),
                                               jnp.array((width, height)), 1.0)
    camera = renderer.Camera.create(view=jnp.asarray(view, jnp.float32), projection=proj,
                                    viewport=viewport)

    @jax.jit
    def depth(positions, tri, camera):
        buffers = renderer.Buffers(zbuffer=jax.lax.full((width, height), 1.0), targets=())
        zbuf, _ = renderer.render(camera, DepthShader, buffers, tri,
                                  DepthExtraInput(position=positions))
        return zbuf

    tri = jnp.asarray(np.ascontiguousarray(np.asarray(faces)[:, ::-1]))
    r = time_compiled(depth, jnp.asarray(verts), tri, camera, repeats=repeats,
                      warmup=1)
    zbuf = np.asarray(r.pop("out"))  # [W, H], y up
    return {"jaxrenderer_ms": r["median_ms"], "jaxrenderer_compile_s": r["compile_s"]}, zbuf.T[::-1]
