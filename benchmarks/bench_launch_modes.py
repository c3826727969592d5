"""The dispatch's launch modes side by side (``pipelines.dispatch.launch_mode``): every
pipeline compiled once per mode, then timed round-robin (one call of each mode in turn), so
the modes share the machine's noise. Also checks that every mode draws the same image.

    python benchmarks/bench_launch_modes.py --scenes foliage room --costs 0 256 --json rows.json

Prints one markdown table; ``--json`` keeps the rows (medians, minima, lanes, chunks, the
largest pixel difference from the loop's image).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import jax
import numpy as np

from jaxrender.parsing import help_summary, parse_spec, resolution_arg
from jaxrender.pipelines import dispatch, get_pipeline, make_config, program
from jaxrender.scene import default_camera
from jaxrender.shading import load_lit_scene
from jaxrender.timing import block, device_description

PIPELINES = ("deferred", "visbuffer", "checkerboard", "dacs", "object_space", "forward",
             "forward:z_prepass=true", "tads")


def compile_modes(scene, camera, spec: str, modes, width: int, height: int) -> dict:
    name, params = parse_spec(spec, "--pipelines")
    cfg = make_config(name, width=width, height=height, **params)
    calls = {}
    for mode in modes:
        os.environ[dispatch.ENV_LAUNCH] = mode
        t0 = time.perf_counter()
        call, _ = program.compile(get_pipeline(name), scene, camera, cfg)
        calls[mode] = (call, time.perf_counter() - t0)
    os.environ.pop(dispatch.ENV_LAUNCH, None)
    return calls


def time_round_robin(calls: dict, scene, camera, repeats: int, warmup: int = 3) -> dict:
    frames = {m: block(c(scene, camera)) for m, (c, _) in calls.items()}
    for _ in range(warmup):
        for c, _ in calls.values():
            block(c(scene, camera))
    samples = {m: [] for m in calls}
    for _ in range(repeats):
        for m, (c, _) in calls.items():
            t0 = time.perf_counter()
            block(c(scene, camera))
            samples[m].append((time.perf_counter() - t0) * 1e3)
    return {m: (frames[m], samples[m]) for m in calls}


def rows_for(scene_name: str, cost: int, spec: str, modes, width, height, repeats) -> list:
    scene = load_lit_scene(scene_name, effects={"shader_cost": cost})
    camera = default_camera(scene)
    calls = compile_modes(scene, camera, spec, modes, width, height)
    timed = time_round_robin(calls, scene, camera, repeats)
    base = np.asarray(timed[modes[0]][0].image)
    rows = []
    for mode, (frame, samples) in timed.items():
        counts = {k: float(np.asarray(v)) for k, v in frame.counts.items() if np.ndim(v) == 0}
        img = np.asarray(frame.image)
        rows.append(dict(
            scene=scene_name, shader_cost=cost, pipeline=spec, mode=mode,
            median_ms=statistics.median(samples), min_ms=min(samples),
            compile_s=calls[mode][1], shade_invocations=counts.get("shade_invocations"),
            lanes=counts.get("lanes", counts.get("dispatch_lanes")),
            max_diff_vs_first=float(np.nanmax(np.abs(img - base))) if img.size else 0.0,
            same_nan=bool(np.array_equal(np.isnan(img), np.isnan(base)))))
    return rows


def table(rows: list, modes) -> str:
    head = ["scene", "cost", "pipeline", *[f"{m} ms" for m in modes],
            *[f"{m} min" for m in modes], "lanes (" + "/".join(modes) + ")", "max diff"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    groups = {}
    for r in rows:
        groups.setdefault((r["scene"], r["shader_cost"], r["pipeline"]), {})[r["mode"]] = r
    for (scene, cost, pipe), by in groups.items():
        med = [f"{by[m]['median_ms']:.2f}" for m in modes if m in by]
        mn = [f"{by[m]['min_ms']:.2f}" for m in modes if m in by]
        lanes = "/".join(f"{by[m]['lanes'] or 0:.0f}" for m in modes if m in by)
        diff = max(by[m]["max_diff_vs_first"] for m in by)
        out.append(f"| {scene} | {cost} | {pipe} | " + " | ".join(med + mn) +
                   f" | {lanes} | {diff:.2g} |")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["foliage"])
    ap.add_argument("--costs", nargs="+", type=int, default=[0])
    ap.add_argument("--pipelines", nargs="+", default=list(PIPELINES))
    ap.add_argument("--modes", nargs="+", default=list(dispatch.LAUNCH_MODES),
                    choices=dispatch.LAUNCH_MODES)
    ap.add_argument("--resolution", type=resolution_arg, default=(1920, 1080))
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    w, h = args.resolution
    print(f"# launch modes, {device_description()}, jax {jax.__version__}, {w}x{h}, "
          f"median of {args.repeats} round-robin calls")
    rows = []
    for scene in args.scenes:
        for cost in args.costs:
            for spec in args.pipelines:
                try:
                    rows += rows_for(scene, cost, spec, args.modes, w, h, args.repeats)
                except Exception as e:  # noqa: BLE001 - report and go on to the next row
                    print(f"{scene} {cost} {spec}: {type(e).__name__}: {e}", flush=True)
                    continue
                print(table(rows[-len(args.modes):], args.modes).splitlines()[-1], flush=True)
                if args.json:
                    with open(args.json, "w") as f:
                        json.dump(rows, f, indent=1)
    print(table(rows, args.modes))


if __name__ == "__main__":
    main()
