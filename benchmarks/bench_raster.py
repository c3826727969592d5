"""Rasterizer benchmark: full visibility (transform, clip, coverage, resolve) per frame.

    python benchmarks/bench_raster.py --preset cpu      # 640x360 10k, brute force 2.5k
    python benchmarks/bench_raster.py --preset gpu      # + 1920x1080 at 164k, 655k, 2.6M

Scenes are heightfield terrains (jaxrender.scene.mesh.terrain_mesh) seen from above at an
angle, so triangle sizes vary across the image. Also times a brute-force rasterizer (every pixel
tests every triangle) on 2.5k triangles to show the gap, and on a GPU checks that the GPU's
triangle ids equal the CPU's.
"""

from __future__ import annotations

import argparse
import os
import sys

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from jaxrender.bench.report import dump, print_table  # noqa: E402
from jaxrender.timing import environment, time_compiled  # noqa: E402

from jaxrender.raster import rasterize_clip  # noqa: E402
from jaxrender.raster.rasterize import (  # noqa: E402
    default_clip_capacity,
    default_work_capacity,
    rasterize_program,
)
from jaxrender.raster.samples import CENTER, to_fixed  # noqa: E402
from jaxrender.raster.setup import SUBPIXEL_BITS, setup_triangles  # noqa: E402
from jaxrender.scene.camera import look_at, world_to_clip  # noqa: E402
from jaxrender.scene.mesh import terrain_mesh  # noqa: E402

PRESETS = {
    "cpu": [(640, 360, 10_000)],
    "gpu": [(640, 360, 10_000), (1920, 1080, 2_500), (1920, 1080, 164_000),
            (1920, 1080, 655_000), (1920, 1080, 2_600_000)],
}


def scene(n_tris: int, width: int, height: int):
    v, f = terrain_mesh(n_tris)
    cam = look_at((0.0, 30.0, 62.0), (0.0, 0.0, -5.0), fov_y_deg=55, near=0.5, far=500)
    clip = world_to_clip(jnp.asarray(v), cam, width / height)
    return clip, jnp.asarray(f)


def static_args(n_tris, width, height):
    return dict(
        width=width, height=height, cull_backfaces=False,
        offsets=to_fixed(CENTER, SUBPIXEL_BITS),
        work_capacity=default_work_capacity(n_tris, width, height),
        clip_capacity=default_clip_capacity(n_tris),
    )


def _brute_chunk(zbuf, s, sx, sy):
    e = (s.edge_a[:, None, :] * sx[None, :, None] + s.edge_b[:, None, :] * sy[None, :, None]
         + s.edge_c[:, None, :])
    inside = jnp.all(e + s.top_left[:, None, :] > 0, axis=-1) & (s.count[:, None] > 0)
    lam = e.astype(jnp.float32) * s.inv_area[:, None, None]
    depth = jnp.clip(jnp.sum(lam * s.z[:, None, :], -1), 0.0, 1.0)
    bits = jax.lax.bitcast_convert_type(depth, jnp.int32).astype(jnp.int64)
    key = jnp.where(inside, (bits << 32) | s.tri[:, None].astype(jnp.int64), jnp.iinfo(jnp.int64).max)
    return jnp.minimum(zbuf, jnp.min(key, axis=0))


@jax.jit
def _brute_force(clip, faces):
    return _brute_force_x64(clip, faces)


def _brute_force_x64(clip, faces):
    width, height = BRUTE_SIZE
    with jax.enable_x64(True):
        n = faces.shape[0]
        s = setup_triangles(clip[faces], jnp.ones((n,), bool), jnp.arange(n, dtype=jnp.int32),
                            width, height, jnp.asarray([128, 128], jnp.int64), False)
        chunk = 16
        pad = -n % chunk
        s = jax.tree_util.tree_map(
            lambda a: jnp.concatenate([a, jnp.zeros((pad,) + a.shape[1:], a.dtype)]), s)
        s = jax.tree_util.tree_map(lambda a: a.reshape((-1, chunk) + a.shape[1:]), s)
        px = jnp.arange(width * height) % width
        py = jnp.arange(width * height) // width
        sx = (px * 256 + 128).astype(jnp.float64)
        sy = (py * 256 + 128).astype(jnp.float64)
        zbuf = jnp.full((width * height,), jnp.iinfo(jnp.int64).max, jnp.int64)
        zbuf, _ = jax.lax.scan(lambda z, part: (_brute_chunk(z, part, sx, sy), None), zbuf, s)
        ids = jnp.where(zbuf == jnp.iinfo(jnp.int64).max, -1, (zbuf & 0xFFFFFFFF).astype(jnp.int32))
        return ids.reshape(height, width)


BRUTE_SIZE = (640, 360)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", choices=sorted(PRESETS), default="cpu")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--no-brute", action="store_true")
    ap.add_argument("--brute-size", default="640x360")
    args = ap.parse_args(argv)
    env = environment()
    print(env)
    rows = []
    for width, height, n in PRESETS[args.preset]:
        clip, faces = scene(n, width, height)
        st = static_args(faces.shape[0], width, height)
        r = time_compiled(rasterize_program, clip, faces, repeats=args.repeats, **st)
        vis = r.pop("out")
        row = dict(resolution=f"{width}x{height}", triangles=int(faces.shape[0]), **r,
                   fragments=int(vis.counts["fragments"]), work_items=int(vis.counts["work_items"]),
                   covered=float(np.mean(np.asarray(vis.tri_id) >= 0)))
        if jax.default_backend() != "cpu" and n <= 700_000:
            cpu = jax.devices("cpu")[0]
            with jax.default_device(cpu):
                ref = rasterize_clip(jax.device_put(clip, cpu), jax.device_put(faces, cpu),
                                     width, height)
            row["ids_equal_cpu"] = float(np.mean(np.asarray(ref.tri_id) == np.asarray(vis.tri_id)))
        rows.append(row)
        print_table([row], list(row))
        sys.stdout.flush()
    if not args.no_brute:
        global BRUTE_SIZE
        bw, bh = BRUTE_SIZE = tuple(int(x) for x in args.brute_size.split("x"))
        clip, faces = scene(2_500, bw, bh)
        r = time_compiled(_brute_force, clip, faces, repeats=max(2, args.repeats // 4))
        ids = r.pop("out")
        times = [r["median_ms"] / 1e3]
        st = static_args(faces.shape[0], bw, bh)
        r = time_compiled(rasterize_program, clip, faces, repeats=args.repeats, **st)
        vis = r.pop("out")
        agree = float(np.mean(np.asarray(ids) == np.asarray(vis.tri_id)))
        rows.append(dict(resolution=f"{bw}x{bh}", triangles=int(faces.shape[0]),
                         median_ms=1e3 * float(np.median(times)), compile_s=0.0,
                         method="brute force", ids_equal_jaxrender=agree))
        rows.append(dict(resolution=f"{bw}x{bh}", triangles=int(faces.shape[0]),
                         median_ms=r["median_ms"], compile_s=r["compile_s"], method="jaxrender"))
        print_table(rows[-2:], ["resolution", "triangles", "method", "median_ms", "ids_equal_jaxrender"])
    print("\n## summary\n")
    print_table(rows, ["resolution", "triangles", "median_ms", "min_ms", "compile_s", "fragments",
                       "work_items", "covered", "ids_equal_cpu", "method"])
    dump(args.json, {"environment": env, "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
