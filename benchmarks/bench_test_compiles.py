"""How long do the test suite's programs take XLA:CPU to compile under each set of XLA flags?

Each variant runs in a fresh process (XLA reads its flags once): every pipeline named renders
the tests' three blended quads (tests/pipelines/transparent_scenes.py) at 32x18, as the tests
do, and the process reports its backend compile seconds (jax's compile events), its first
call's wall time and a second call's. The images of every variant are compared bit for bit
with the first variant's. Variants run in the order A B B A (then each row is the mean of its
two runs), so that neither gains from running second. Usage:

    JAX_PLATFORMS=cpu python benchmarks/bench_test_compiles.py [--pipelines deferred forward]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
PIPELINES = ("reference", "forward", "deferred", "visbuffer", "checkerboard", "dacs",
             "object_space")
# The test suite's flags (tests/conftest.py) and the ones it was measured against.
VARIANTS = {
    "O0": "--xla_backend_optimization_level=0",
    "suite": "--xla_backend_optimization_level=0 --xla_cpu_use_fusion_emitters=false "
             "--xla_cpu_max_isa=AVX",
    "O0, loop emitters": "--xla_backend_optimization_level=0 "
                         "--xla_cpu_use_fusion_emitters=false",
    "default": "",
    "default, loop emitters": "--xla_cpu_use_fusion_emitters=false",
}


def child(pipelines: list[str], out: str) -> None:
    """Render each pipeline once (compiling) and again (compiled); print one JSON line."""
    import jax

    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.study.compile_cache import BACKEND_COMPILE_EVENT
    from tests.pipelines.transparent_scenes import THREE, layered_quads

    compile_s = [0.0]

    def on_duration(event: str, duration: float, **_) -> None:
        if event == BACKEND_COMPILE_EVENT:
            compile_s[0] += duration

    jax.monitoring.register_event_duration_secs_listener(on_duration)
    scene = layered_quads(THREE, (0, 1, 2))

    def render_all() -> dict:
        images = {}
        for name in pipelines:
            params = {"k": 1} if name == "reference" else {}
            cfg = make_config(name, width=32, height=18, **params)
            images[name] = np.asarray(get_pipeline(name).render(scene, scene.camera, cfg).image)
        return images

    start = time.perf_counter()
    images = render_all()
    first = time.perf_counter() - start
    start = time.perf_counter()
    render_all()
    again = time.perf_counter() - start
    np.savez(out, **images)
    print(json.dumps({"compile_s": compile_s[0], "first_s": first, "again_s": again}))


def run_variant(flags: str, pipelines: list[str], out: Path) -> dict:
    env = dict(os.environ, XLA_FLAGS=flags, JAX_PLATFORMS="cpu", PYTHONPATH=str(REPO),
               JAXRENDER_COMPILE_PROCESSES="0")
    done = subprocess.run([sys.executable, __file__, "--child", str(out), "--pipelines",
                           *pipelines], env=env, capture_output=True, text=True, cwd=REPO)
    if done.returncode:
        raise SystemExit(f"XLA_FLAGS={flags!r} failed:\n{done.stdout}\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--pipelines", nargs="+", default=list(PIPELINES), choices=PIPELINES)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS)[:2], choices=list(VARIANTS),
                    help="the flag sets to compare (default: the suite's and -O0 alone)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.pipelines, args.child)
        return
    names = args.variants
    runs: dict[str, list[dict]] = {n: [] for n in names}
    with tempfile.TemporaryDirectory() as tmp:
        for i, name in enumerate(names + names[::-1]):
            out = Path(tmp) / f"{i}.npz"
            runs[name].append(dict(run_variant(VARIANTS[name], args.pipelines, out), out=out))
        first = np.load(runs[names[0]][0]["out"])
        print(f"{os.cpu_count()} CPU cores; pipelines: {' '.join(args.pipelines)}; "
              "each row the mean of two runs (A B B A)")
        print("| XLA flags | compile s | first call s | again s | images as the first row's |")
        print("|---|---:|---:|---:|---|")
        for name in names:
            mean = {k: np.mean([r[k] for r in runs[name]]) for k in
                    ("compile_s", "first_s", "again_s")}
            same = all(np.array_equal(first[p], np.load(r["out"])[p])
                       for r in runs[name] for p in args.pipelines)
            print(f"| {VARIANTS[name] or '(none)'} | {mean['compile_s']:.1f} | "
                  f"{mean['first_s']:.1f} | {mean['again_s']:.3f} | "
                  f"{'bit for bit' if same else 'DIFFERENT'} |")


if __name__ == "__main__":
    main()
