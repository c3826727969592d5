"""Frame time of the forward, deferred and visibility-buffer pipelines per scene (honest timing:
AOT compile timed apart, warm-up, block_until_ready, median of repeats). Prints a markdown table
with the device and JAX version, and the shading counts beside the times.

    python benchmarks/bench_pipelines.py --scenes foliage room many_small --width 320 \
        --height 180 --repeats 10
    python benchmarks/bench_pipelines.py --variants forward forward:z_prepass=true visbuffer:vrs=fixed
"""

from __future__ import annotations

import argparse

from jaxrender.bench.pipelines import parse_spec as parse_variant
from jaxrender.pipelines import get_pipeline, make_config, program
from jaxrender.shading import load_lit_scene
from jaxrender.timing import environment, time_call

DEFAULT_VARIANTS = ("forward", "forward:z_prepass=true", "deferred", "visbuffer",
                    "visbuffer:vrs=fixed")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["foliage", "room", "spheres"])
    ap.add_argument("--variants", nargs="+", default=list(DEFAULT_VARIANTS))
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=90)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args(argv)
    info = environment()
    print(f"device: {info['device']}, jax {info['jax_version']}, {a.width}x{a.height}, "
          f"median of {a.repeats} after 1 warm-up\n")
    print("| scene | pipeline | frame ms | compile ms | invocations | helper lanes | "
          "overshading | waves | lane util | bytes |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene_name in a.scenes:
        scene = load_lit_scene(scene_name)
        for variant in a.variants:
            name, params = parse_variant(variant)
            cfg = make_config(name, width=a.width, height=a.height, **params)
            call, compile_ms = program.compile(get_pipeline(name), scene, scene.camera, cfg)
            frame, ms, _ = time_call(call, scene, scene.camera, repeats=a.repeats, warmup=1)
            c = {k: float(v) for k, v in frame.counts.items()}
            print(f"| {scene_name} | {variant} | {ms:.2f} | {compile_ms:.0f} | "
                  f"{c['shade_invocations']:.0f} | {c['helper_lanes']:.0f} | "
                  f"{c['overshading']:.3f} | {c['waves']:.0f} | {c['lane_utilization']:.3f} | "
                  f"{c['bytes_intermediate']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
