"""Rasterizer throughput: full visibility (transform-free: clip, coverage, resolve) against
triangle count and resolution, on the benchmark terrain that every raster benchmark draws
(``jaxrender bench``, benchmarks/bench_raster.py, bench_peers.py, bench_scale.py and the
profilers), so that their numbers describe the same frame."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.timing import time_compiled
from jaxrender.raster.rasterize import (default_clip_capacity, default_work_capacity,
                                        rasterize_program)
from jaxrender.raster.samples import CENTER, to_fixed
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene.camera import look_at, world_to_clip
from jaxrender.scene.mesh import terrain_mesh

# (triangles, width, height); the full sweeps are the GPU targets of benchmarks/RESULTS.md,
# --quick is for a CPU.
TRIANGLE_SWEEP = [(10_000, 1920, 1080), (40_000, 1920, 1080), (164_000, 1920, 1080),
                  (655_000, 1920, 1080), (2_600_000, 1920, 1080)]
RESOLUTION_SWEEP = [(164_000, 640, 360), (164_000, 1280, 720), (164_000, 2560, 1440),
                    (164_000, 3840, 2160), (2_600_000, 3840, 2160)]
QUICK = [(2_500, 160, 90), (10_000, 320, 180)]


def terrain_camera():
    """The benchmark terrain's camera: the terrain seen from above at an angle."""
    return look_at((0.0, 30.0, 62.0), (0.0, 0.0, -5.0), fov_y_deg=55, near=0.5, far=500)


def terrain_clip(n_tris: int, width: int, height: int):
    """(clip float32[V,4], faces int32[T,3]) of the benchmark terrain of about ``n_tris``
    triangles through ``terrain_camera`` at this image size."""
    v, f = terrain_mesh(n_tris)
    clip = world_to_clip(jnp.asarray(v), terrain_camera(), width / height)
    return clip, jnp.asarray(f)


def static_args(n_tris: int, width: int, height: int) -> dict:
    return dict(width=width, height=height, cull_backfaces=False,
                offsets=to_fixed(CENTER, SUBPIXEL_BITS),
                work_capacity=default_work_capacity(n_tris, width, height),
                clip_capacity=default_clip_capacity(n_tris))


def time_raster(n_tris: int, width: int, height: int, repeats: int = 10) -> dict:
    clip, faces = terrain_clip(n_tris, width, height)
    r = time_compiled(rasterize_program, clip, faces, repeats=repeats,
                      **static_args(faces.shape[0], width, height))
    vis = r.pop("out")
    mtri = faces.shape[0] / (r["median_ms"] * 1e3)
    return dict(resolution=f"{width}x{height}", triangles=int(faces.shape[0]), **r,
                mtris_per_s=mtri, mpix_per_s=width * height / (r["median_ms"] * 1e3),
                fragments=int(vis.counts["fragments"]), work_items=int(vis.counts["work_items"]),
                covered=float(np.mean(np.asarray(vis.tri_id) >= 0)))


COLUMNS = ["resolution", "triangles", "median_ms", "min_ms", "compile_s", "mtris_per_s",
           "mpix_per_s", "work_items", "covered", "temp_mib"]
