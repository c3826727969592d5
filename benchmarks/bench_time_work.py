"""Frame time against shading work: every pipeline on a few scenes at a few shader costs, and
per (scene, pipeline) a least-squares line through (work, ms): the fixed cost and the slope.

    python benchmarks/bench_time_work.py --scenes foliage terrain --costs 0 8 32 --out rows.jsonl
    python benchmarks/bench_time_work.py --frames 8 ...   # each frame inside an 8-frame sequence

Without ``--frames`` a frame is one single-frame call, whose per-call overhead (1.2-2.1 ms on
an H200 at 1080p, RESULTS.md) adds to every intercept; with it, the time per frame of one
sequence program, as studies time frames.

Work is ``shade_invocations x (1 + shader_cost)`` (one unit: one light layer evaluated at one
shaded point, ``Effects.shader_cost``). ``visibility`` is the visibility pass alone (what
deferred, checkerboard and DACS rasterize before shading), the floor of every fixed cost;
it and the reference are measured at the first cost only.
Rows are appended to ``--out`` as they are measured, so a run cut short keeps what it did.
"""

from __future__ import annotations

import argparse
import json
import time

import jax
import numpy as np

from jaxrender.parsing import help_summary, parse_spec, resolution_arg
from jaxrender.study.shader_cost import shading_work
from jaxrender.study.time_fit import fit_line
from jaxrender.timing import block, device_description, time_call

DEFAULT_PIPELINES = ("visibility", "forward", "forward:z_prepass=true", "deferred", "visbuffer",
                     "checkerboard", "dacs", "object_space", "reference")
SINGLE_COST = ("visibility", "reference")  # measured at the first cost only


def default_outputs() -> str:
    """"images" where the tree on the path can time a program without its counts, else
    "all" (a tree from before the twenty-fourth session)."""
    from jaxrender.pipelines import program

    return "images" if hasattr(program, "OUTPUTS") else "all"


def visibility_program(scene, camera, cfg):
    from jaxrender.pipelines.visibility import visibility

    return jax.jit(lambda s, c: visibility(s, c, cfg).tri_id)


def visibility_sequence_program(scene, path, cfg):
    """The visibility pass of every camera of ``path`` in one program, as a sequence runs it."""
    from jaxrender.pipelines.visibility import visibility

    return jax.jit(lambda s, p: jax.lax.map(lambda c: visibility(s, c, cfg).tri_id, p))


def measure(scene_name: str, spec: str, cost: int, width: int, height: int, repeats: int,
            frames: int = 0, outputs: str = "images"):
    """One row: median and min ms of the steady-state frame, compile seconds, counts. With
    ``frames``, the frame's time inside a sequence of that many frames (a pan at 1 px/frame,
    one program, as studies time a frame): the sequence's time over ``frames``, counts the mean
    over its frames. Without, one single-frame call (its per-call overhead included).
    ``outputs="images"``: the timed program returns the images alone (the counts come from
    one call of the instrumented program); ``"all"``: the instrumented program is timed (a
    tree from before the twenty-fourth session knows no other)."""
    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.pipelines import program
    from jaxrender.scene import default_camera
    from jaxrender.scene.camera_path import pan
    from jaxrender.shading import load_lit_scene

    scene = load_lit_scene(scene_name, effects={"shader_cost": cost})
    camera = default_camera(scene)
    cams = pan(camera, frames, 1.0, height).cameras if frames else camera
    per = max(frames, 1)
    name, params = parse_spec(spec, "--pipelines")
    row = dict(scene=scene_name, pipeline=spec, shader_cost=cost, resolution=f"{width}x{height}",
               frames=frames)
    t0 = time.perf_counter()
    if name == "visibility":
        cfg = make_config("deferred", width=width, height=height)
        make = visibility_sequence_program if frames else visibility_program
        call = make(scene, cams, cfg).lower(scene, cams).compile()
        row["compile_s"] = time.perf_counter() - t0
        _, median, samples = time_call(call, scene, cams, repeats=repeats, warmup=2)
        return dict(row, median_ms=median / per, min_ms=min(samples) / per, shade_invocations=0)
    cfg = make_config(name, width=width, height=height, **params)
    pipe = get_pipeline(name)
    row["outputs"] = outputs
    call, _ = program.compile(pipe, scene, cams, cfg, sequence=bool(frames))
    row["compile_s"] = time.perf_counter() - t0
    if outputs == "images":  # timed with the images alone; the counts from one call of `call`
        frame = block(call(scene, cams))
        t0 = time.perf_counter()
        call, _ = program.compile(pipe, scene, cams, cfg, sequence=bool(frames),
                                  outputs="images")
        row["compile_timed_s"] = time.perf_counter() - t0
    frame_or_image, median, samples = time_call(call, scene, cams, repeats=repeats, warmup=2)
    frame = frame if outputs == "images" else frame_or_image
    counts = {k: float(np.mean(np.asarray(v))) for k, v in frame.counts.items()
              if np.ndim(v) == (1 if frames else 0)}
    keep = ("shade_invocations", "lanes", "dispatch_lanes", "fragments", "waves", "overflow")
    return dict(row, median_ms=median / per, min_ms=min(samples) / per,
                **{k: counts[k] for k in keep if k in counts})


def fit(rows):
    """``study.time_fit.fit_line`` of every (scene, pipeline) with two or more shader costs."""
    groups = {}
    for r in rows:
        if "median_ms" in r and r["pipeline"] not in SINGLE_COST:
            groups.setdefault((r["scene"], r["pipeline"]), []).append(r)
    out = {}
    for key, rs in groups.items():
        work = [shading_work(r["shade_invocations"], r["shader_cost"]) for r in rs]
        if len(set(work)) > 1:
            out[key] = fit_line(work, [r["median_ms"] for r in rs])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["foliage", "terrain"])
    ap.add_argument("--pipelines", nargs="+", default=list(DEFAULT_PIPELINES))
    ap.add_argument("--costs", nargs="+", type=int, default=[0, 8, 32])
    ap.add_argument("--resolution", type=resolution_arg, default=(1920, 1080))
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--budget", type=float, default=0.0, help="seconds; 0: no limit")
    ap.add_argument("--out", default="time_work.jsonl")
    ap.add_argument("--label", default="", help="a tag written into every row (e.g. 'before')")
    ap.add_argument("--frames", type=int, default=0,
                    help="time each frame inside a sequence of this many frames (how studies "
                         "time a frame); 0: single-frame calls")
    ap.add_argument("--outputs", choices=("images", "all"), default=None,
                    help="what the timed program returns: the images alone (the default), or "
                         "the counts and views too (as every time before the twenty-fourth "
                         "session; the default for an older tree, which knows no other)")
    a = ap.parse_args(argv)
    a.outputs = a.outputs or default_outputs()
    w, h = a.resolution
    t_start = time.time()
    print(f"device: {device_description()}, jax {jax.__version__}, {a.label}", flush=True)
    rows = []
    for scene in a.scenes:
        for spec in a.pipelines:
            for cost in (a.costs[:1] if spec in SINGLE_COST else a.costs):
                if a.budget and time.time() - t_start > a.budget:
                    row = dict(scene=scene, pipeline=spec, shader_cost=cost, skipped="budget")
                else:
                    try:
                        row = measure(scene, spec, cost, w, h, a.repeats, a.frames,
                                      a.outputs)
                    except Exception as e:  # noqa: BLE001 - a failed row is kept with its reason
                        row = dict(scene=scene, pipeline=spec, shader_cost=cost,
                                   error=f"{type(e).__name__}: {e}"[:300])
                row["label"] = a.label
                rows.append(row)
                with open(a.out, "a") as f:
                    f.write(json.dumps(row) + "\n")
                print(json.dumps(row), flush=True)
    for (scene, spec), f in fit(rows).items():
        if f.n > 2:
            line = (f"fixed {f.intercept_ms:.3f} +- {f.intercept_se:.3f} ms, slope "
                    f"{f.slope_ms:.4f} +- {f.slope_se:.4f} ms/M, R^2 {f.r2:.3f}")
        else:  # a line through two points: no residual, so no standard error
            line = (f"fixed {f.intercept_ms:.3f} ms, slope {f.slope_ms:.4f} ms/M (two costs: "
                    "no standard error)")
        print(f"fit {a.label} {scene} {spec}: {line}"
              + ("" if f.linear else f" (not linear: {f.note})"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
