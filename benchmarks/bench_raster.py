"""Rasterizer benchmark: full visibility (transform, clip, coverage, resolve) per frame.

    python benchmarks/bench_raster.py --preset cpu      # 640x360 10k, brute force 2.5k
    python benchmarks/bench_raster.py --preset gpu      # + 1920x1080 at 164k, 655k, 2.6M
    python benchmarks/bench_raster.py --preset tiny --brute-size 64x36   # a CPU smoke run

Scenes are the benchmark terrain (``jaxrender.bench.raster.terrain_clip``: a heightfield seen
from above at an angle, so triangle sizes vary across the image), as in ``jaxrender bench``.
Also times a brute-force rasterizer (every pixel tests every triangle) on 2.5k triangles to show
the gap, and on a GPU checks that the GPU's triangle ids equal the CPU's.
"""

from __future__ import annotations

import argparse
import sys
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.bench.raster import static_args, terrain_clip
from jaxrender.bench.report import dump, print_table
from jaxrender.parsing import resolution_arg
from jaxrender.raster import rasterize_clip
from jaxrender.raster.rasterize import rasterize_program
from jaxrender.raster.setup import setup_triangles
from jaxrender.timing import environment, time_compiled

PRESETS = {
    "tiny": [(64, 36, 500)],  # a smoke run, with --brute-size 64x36
    "cpu": [(640, 360, 10_000)],
    "gpu": [(640, 360, 10_000), (1920, 1080, 2_500), (1920, 1080, 164_000),
            (1920, 1080, 655_000), (1920, 1080, 2_600_000)],
}
BRUTE_TRIANGLES = 2_500
BRUTE_CHUNK = 16  # triangles tested against every pixel at once
NO_HIT = np.iinfo(np.int64).max


def _brute_chunk(zbuf, s, sx, sy):
    e = (s.edge_a[:, None, :] * sx[None, :, None] + s.edge_b[:, None, :] * sy[None, :, None]
         + s.edge_c[:, None, :])
    inside = jnp.all(e + s.top_left[:, None, :] > 0, axis=-1) & (s.count[:, None] > 0)
    lam = e.astype(jnp.float32) * s.inv_area[:, None, None]
    depth = jnp.clip(jnp.sum(lam * s.z[:, None, :], -1), 0.0, 1.0)
    bits = jax.lax.bitcast_convert_type(depth, jnp.int32).astype(jnp.int64)
    key = jnp.where(inside, (bits << 32) | s.tri[:, None].astype(jnp.int64), NO_HIT)
    return jnp.minimum(zbuf, jnp.min(key, axis=0))


@partial(jax.jit, static_argnames=("width", "height"))
def brute_force_ids(clip, faces, *, width: int, height: int):
    """int32[H, W] triangle ids (-1: empty) from testing every pixel against every triangle,
    nearest depth first: the rasterizer without any of its work reduction, for scale."""
    with jax.enable_x64(True):
        n = faces.shape[0]
        s = setup_triangles(clip[faces], jnp.ones((n,), bool), jnp.arange(n, dtype=jnp.int32),
                            width, height, jnp.asarray([128, 128], jnp.int64), False)
        pad = -n % BRUTE_CHUNK
        s = jax.tree_util.tree_map(
            lambda a: jnp.concatenate([a, jnp.zeros((pad,) + a.shape[1:], a.dtype)]), s)
        s = jax.tree_util.tree_map(lambda a: a.reshape((-1, BRUTE_CHUNK) + a.shape[1:]), s)
        px = jnp.arange(width * height) % width
        py = jnp.arange(width * height) // width
        sx = (px * 256 + 128).astype(jnp.float64)
        sy = (py * 256 + 128).astype(jnp.float64)
        zbuf = jnp.full((width * height,), NO_HIT, jnp.int64)
        zbuf, _ = jax.lax.scan(lambda z, part: (_brute_chunk(z, part, sx, sy), None), zbuf, s)
        ids = jnp.where(zbuf == NO_HIT, -1, (zbuf & 0xFFFFFFFF).astype(jnp.int32))
        return ids.reshape(height, width)


def raster_row(width: int, height: int, n: int, repeats: int) -> dict:
    """The full visibility of the terrain at this size, timed; on a GPU (up to 700k triangles)
    also the fraction of triangle ids equal to the CPU's."""
    clip, faces = terrain_clip(n, width, height)
    st = static_args(faces.shape[0], width, height)
    r = time_compiled(rasterize_program, clip, faces, repeats=repeats, **st)
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
    return row


def brute_force_rows(width: int, height: int, repeats: int) -> list[dict]:
    """The brute-force rasterizer and jaxrender's on the same small terrain, and how many of
    their triangle ids agree."""
    clip, faces = terrain_clip(BRUTE_TRIANGLES, width, height)
    brute = time_compiled(brute_force_ids, clip, faces, repeats=max(2, repeats // 4),
                          width=width, height=height)
    ids = brute.pop("out")
    ours = time_compiled(rasterize_program, clip, faces, repeats=repeats,
                         **static_args(faces.shape[0], width, height))
    vis = ours.pop("out")
    agree = float(np.mean(np.asarray(ids) == np.asarray(vis.tri_id)))
    base = dict(resolution=f"{width}x{height}", triangles=int(faces.shape[0]))
    return [dict(base, median_ms=brute["median_ms"], compile_s=brute["compile_s"],
                 method="brute force", ids_equal_jaxrender=agree),
            dict(base, median_ms=ours["median_ms"], compile_s=ours["compile_s"],
                 method="jaxrender")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--preset", choices=sorted(PRESETS), default="cpu")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--no-brute", action="store_true")
    ap.add_argument("--brute-size", type=resolution_arg, default="640x360")
    args = ap.parse_args(argv)
    env = environment()
    print(env)
    rows = []
    for width, height, n in PRESETS[args.preset]:
        rows.append(raster_row(width, height, n, args.repeats))
        print_table([rows[-1]], list(rows[-1]))
        sys.stdout.flush()
    if not args.no_brute:
        rows += brute_force_rows(*args.brute_size, args.repeats)
        print_table(rows[-2:], ["resolution", "triangles", "method", "median_ms",
                                "ids_equal_jaxrender"])
    print("\n## summary\n")
    print_table(rows, ["resolution", "triangles", "median_ms", "min_ms", "compile_s", "fragments",
                       "work_items", "covered", "ids_equal_cpu", "method"])
    dump(args.json, {"environment": env, "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
