"""Object-space shading on built-in scenes: shadels per pixel, chunk fill, MIP overheads, bias
under a shrinking store, and time vs deferred. Prints a markdown table.

    python benchmarks/bench_object_space.py [--size 128x72] [--scenes stripes,spheres,room]
        [--repeats 3] [--store-per-pixel 6,1]

Runs on whatever device JAX picks (CPU by default). Timing: one warm-up call (compile reported
apart), then the median of ``repeats`` calls with block_until_ready; the sheet build (host,
cached) is reported apart as well.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines import object_space as osp
from jaxrender.scene.builtin import builtin_scene
from jaxrender.shading import with_shadow_map
from jaxrender.timing import device_description, time_first_call


def _time(fn, repeats):
    """(output, median ms, first call minus the median in ms)."""
    r = time_first_call(fn, repeats)
    return r["out"], r["median_ms"], r["compile_s"] * 1e3


def main(argv=None):
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--size", type=resolution_arg, default="128x72")
    ap.add_argument("--scenes", default="stripes,spheres,room,terrain")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--store-per-pixel", default="6,1",
                    help="store capacities to try, in shadels per pixel")
    a = ap.parse_args(argv)
    w, h = a.size
    print(f"device: {device_description()}, {w}x{h}\n")
    print("| scene | store/px | sheets (res, source) | sheet build s | covered px | shadels/px "
          "| shaded | chunk fill | trilinear x | MIP chain mem x | bias | os ms | compile s "
          "| deferred ms |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    dr = get_pipeline("deferred").render
    for name in a.scenes.split(","):
        scene = builtin_scene(name)
        if scene.effects.shadows:
            scene = with_shadow_map(scene)
        dcfg = make_config("deferred", width=w, height=h)
        _, d_ms, _ = _time(lambda s=scene, c=dcfg: dr(s, s.camera, c).image, a.repeats)
        for spp in (float(s) for s in a.store_per_pixel.split(",")):
            cfg = osp.ObjectSpaceConfig(width=w, height=h, store_shadels=int(spp * w * h))
            t0 = time.perf_counter()
            sheet = osp.prepare(scene, cfg)
            build_s = time.perf_counter() - t0
            res = np.asarray(sheet.obj_res)
            srcs = ",".join(sorted(set(sheet.sources)))
            sheets = f"{len(res)} x {res.min()}..{res.max()} ({srcs})"
            frame, ms, comp = _time(lambda s=scene, c=cfg: osp.render(s, s.camera, c), a.repeats)
            c = {k: float(v) for k, v in frame.counts.items()}
            print(f"| {name} | {spp:g} | {sheets} | {build_s:.1f} | {c['covered_pixels']:.0f} "
                  f"| {c['shadels_per_pixel']:.2f} | {c['shade_invocations']:.0f} "
                  f"| {c['chunk_fill']:.2f} | {c['trilinear_overhead']:.2f} "
                  f"| {c['mip_chain_memory']:.3f} | {c['mip_bias']:.2f} | {ms:.1f} "
                  f"| {comp / 1e3:.1f} | {d_ms:.1f} |", flush=True)


if __name__ == "__main__":
    main()
