"""Deferred's attribute pass in several G-buffer layouts, over the whole screen as deferred
runs it on a mostly covered scene (``shade_dense`` in place): the points' 20 channels packed
into rows (the layout before the twenty-fifth session), one array per field
(``gbuffer_fields``, the layout since), one plane per channel, the planes stacked, and the
fields stored (``fusion.materialize_all``) before the rows are packed.

    python benchmarks/bench_gbuffer_layout.py --scenes room glass --resolution 1920x1080

On an H100 the concatenation was one kernel of 0.55 ms on room and on glass (RESULTS.md,
twenty-fourth session), several times what writing 20 channels of 1080p costs; one array a
field took 0.58-0.62x the rows' time (twenty-fifth session). Each variant's median ms of 20 calls,
alternated over 3 rounds.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import jax
import jax.numpy as jnp

from jaxrender.fusion import materialize_all
from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.pipelines import make_config
from jaxrender.pipelines.gbuffer import GBUFFER_CHANNELS, gbuffer_fields
from jaxrender.pipelines.visibility import visibility
from jaxrender.scene import default_camera
from jaxrender.shading import load_lit_scene
from jaxrender.shading.surface import surface_points
from jaxrender.timing import device_description


def variants(camera, vis, n: int) -> dict:
    tri = vis.tri_id.reshape(-1)
    flat = [a.reshape(n, 3) for a in (vis.bary, vis.dbary_dx, vis.dbary_dy)]
    active = tri >= 0

    def points(s):
        p = surface_points(s, camera, tri, *flat)
        return dataclasses.replace(p, valid=p.valid & active)

    def keep(v):
        return jnp.where(active.reshape(active.shape + (1,) * (v.ndim - 1)), v, 0.0)

    def planes(s):
        fields = gbuffer_fields(points(s))
        return [keep(c) for v in fields for c in jnp.split(v, v.shape[1], axis=1)]

    return {
        "rows (concatenated)": lambda s: keep(jnp.concatenate(gbuffer_fields(points(s)), 1)),
        "one array a field": lambda s: tuple(keep(v) for v in gbuffer_fields(points(s))),
        "one plane a channel": lambda s: tuple(p[:, 0] for p in planes(s)),
        "planes stacked": lambda s: jnp.concatenate([p.T for p in planes(s)], axis=0),
        "fields stored, then rows": lambda s: keep(jnp.concatenate(
            materialize_all(*gbuffer_fields(points(s))), axis=1)),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["room", "glass"])
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args(argv)
    w, h = a.resolution
    print(f"device: {device_description()}, jax {jax.__version__}; {w}x{h}, "
          f"{GBUFFER_CHANNELS} channels, median ms of {a.repeats} calls, best of {a.rounds}")
    print("| scene | layout | ms |\n|---|---|---:|", flush=True)
    for name in a.scenes:
        scene = load_lit_scene(name)
        camera = default_camera(scene)
        cfg = make_config("deferred", width=w, height=h)
        vis = jax.jit(lambda s, c: visibility(s, c, cfg))(scene, camera)
        progs = {k: jax.jit(f).lower(scene).compile()
                 for k, f in variants(camera, vis, w * h).items()}
        best = {k: float("inf") for k in progs}
        for _ in range(a.rounds):
            for k, prog in progs.items():
                jax.block_until_ready(prog(scene))
                samples = []
                for _ in range(a.repeats):
                    t = time.perf_counter()
                    jax.block_until_ready(prog(scene))
                    samples.append((time.perf_counter() - t) * 1e3)
                best[k] = min(best[k], statistics.median(samples))
        for k, ms in best.items():
            print(f"| {name} | {k} | {ms:.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
