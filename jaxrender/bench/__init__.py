"""``jaxrender bench``: rasterizer throughput, pipeline frame times, metric times, compile times
and peak device memory, printed as markdown tables and written as JSON.

    jaxrender bench --quick                    # a minute on a laptop CPU
    jaxrender bench --json bench.json          # the full sweeps (for the GPU)
    python -m jaxrender.bench --sections raster --json raster.json

The raster sweeps draw the benchmark terrain (``bench.raster.terrain_clip``); pipelines run
on every built-in scene from its default camera, every (scene, pipeline) a row: a scene's
programs compile side by side, then each is timed alone, and a row carries its compile time
apart from its steady-state median. No default budget: every row runs to its repeats
(``--budget`` caps a row's timed repeats, never skips one). This module imports nothing heavy
until ``run``.
"""

from __future__ import annotations

import argparse

from jaxrender.parsing import help_summary, positive_int_arg, resolution_arg

SECTIONS = ("raster", "pipelines", "metrics")


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    p.add_argument("--quick", action="store_true",
                   help="small sizes (a CPU smoke run) instead of the full sweeps")
    p.add_argument("--json", metavar="PATH", help="write every row and the environment here")
    p.add_argument("--sections", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    p.add_argument("--resolution", type=resolution_arg, help="pipelines: WxH (default 1920x1080, "
                   "quick 160x90)")
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="pipelines: scenes as name or name:key=value,... (default: all built-ins "
                        "plus many_small:n_triangles=100000; quick: terrain)")
    p.add_argument("--pipelines", nargs="+", metavar="PIPELINE",
                   help="pipelines: names or name:key=value,... (default: every registered one)")
    p.add_argument("--repeats", type=int, help="timed repeats per row (default 10, quick 3)")
    p.add_argument("--budget", type=float, default=0.0, metavar="SECONDS",
                   help="pipelines: seconds of timed repeats per row at most; a slow row "
                        "takes fewer repeats, at least one (0: all --repeats). Every row runs: "
                        "the budget never skips a scene or a pipeline")
    p.add_argument("--compile-workers", type=positive_int_arg, default=None, metavar="N",
                   help="pipelines: programs of a scene compiled side by side before any is "
                        "timed (default: min(8, cores); 1: one after another, compile_s "
                        "then is a lone compile's)")
    p.add_argument("--metric-frames", type=int, help="metrics: batch size (default 60, quick 2)")
    return p


def run(a: argparse.Namespace) -> int:
    import os
    import sys
    import time

    import datetime
    import platform

    import jax

    from jaxrender import timing
    from jaxrender.bench import report

    t_start = time.monotonic()
    env = {**timing.environment(), "devices": jax.device_count(),
           "date": datetime.date.today().isoformat(), "host": platform.node()}
    print(f"# jaxrender bench\n\n{env}\n", flush=True)
    repeats = a.repeats or (3 if a.quick else 10)
    out = {"environment": env, "quick": bool(a.quick), "sections": {}, "memory": {}}

    def section(name, rows, columns):
        print(f"\n## {name}\n", flush=True)
        print("| " + " | ".join(columns) + " |\n|" + "|".join("---" for _ in columns) + "|",
              flush=True)
        kept = []
        for row in rows:
            kept.append(row)
            print("| " + " | ".join(report.fmt(row.get(c)) for c in columns) + " |", flush=True)
            report.dump(a.json, out | {"sections": out["sections"] | {name: kept}})
        out["sections"][name] = kept
        out["memory"][name] = timing.peak_memory()
        print(f"\npeak device memory after {name}: {out['memory'][name]}", flush=True)

    if "raster" in a.sections:
        from jaxrender.bench import raster

        sizes = raster.QUICK if a.quick else raster.TRIANGLE_SWEEP + raster.RESOLUTION_SWEEP

        def raster_rows():
            for n, w, h in sizes:
                try:
                    yield raster.time_raster(n, w, h, repeats)
                except Exception as e:  # noqa: BLE001 - e.g. out of memory at 4K x 2.6M
                    yield dict(resolution=f"{w}x{h}", triangles=n,
                               skipped=f"{type(e).__name__}: {e}"[:200])

        section("raster", raster_rows(), raster.COLUMNS + ["skipped"])

    if "pipelines" in a.sections:
        from jaxrender.bench import pipelines

        w, h = a.resolution or ((160, 90) if a.quick else (1920, 1080))
        scenes = a.scenes or (["terrain"] if a.quick else pipelines.default_scene_specs())
        pipes = a.pipelines or pipelines.default_pipeline_specs()
        workers = a.compile_workers or max(1, min(8, os.cpu_count() or 1))
        section("pipelines", pipelines.time_pipelines(
            scenes, pipes, w, h, repeats=repeats, budget_s=a.budget if a.budget > 0 else None,
            compile_workers=workers), pipelines.COLUMNS)

    if "metrics" in a.sections:
        from jaxrender.bench import metrics

        w, h = (320, 180) if a.quick else (1920, 1080)
        frames = a.metric_frames or (2 if a.quick else 60)
        section("metrics", metrics.time_metrics(w, h, frames, repeats), metrics.COLUMNS)

    out["total_s"] = time.monotonic() - t_start
    report.dump(a.json, out)
    print(f"\ntotal {out['total_s']:.1f} s" + (f"; wrote {a.json}" if a.json else ""))
    sys.stdout.flush()
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="jaxrender bench", description=help_summary(__doc__))
    return run(add_arguments(p).parse_args(argv))
