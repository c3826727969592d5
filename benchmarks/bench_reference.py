"""Time the reference pipeline, and measure its convergence (PSNR between k and 2k).

    python benchmarks/bench_reference.py --scenes spheres room --width 320 --height 180 --k 4 8
    python benchmarks/bench_reference.py --convergence --scenes spheres --k 4 8 16

Prints markdown tables. Time: compile apart (k is traced, so one compile serves every k),
one warm-up call, then the median of --repeats calls with block_until_ready. Convergence: LDR
PSNR (clamp, sRGB) between the images at k and 2k samples per pixel side. Runs anywhere: CPU
by default (JAX_PLATFORMS), a GPU when jax has one.
"""

from __future__ import annotations

import argparse
import dataclasses

import jax

from jaxrender.parsing import help_summary
from jaxrender.pipelines import get_pipeline, program
from jaxrender.pipelines.reference import ReferenceConfig, ldr_psnr
from jaxrender.scene import default_camera, list_builtin_scenes
from jaxrender.shading import load_lit_scene
from jaxrender.timing import environment, time_call


def bench(scenes, width, height, ks, repeats) -> None:
    print(f"device: {environment()['device']}, jax {jax.__version__}\n")
    print("| scene | resolution | k | samples/px | compile s | median ms | shaded samples "
          "| Msamples/s |")
    print("|---|---|---|---|---|---|---|---|")
    pipe = get_pipeline("reference")
    for name in scenes:
        scene = load_lit_scene(name)
        cam = default_camera(scene)
        base = ReferenceConfig(width=width, height=height, k=ks[0])
        _, compile_ms = program.compile(pipe, scene, cam, base)
        compile_s = compile_ms / 1e3
        for k in ks:
            # k is traced: every k runs the one program (its jit compile is in the warm-up call)
            cfg = dataclasses.replace(base, k=k)
            frame, ms, _ = time_call(pipe.render, scene, cam, cfg, repeats=repeats, warmup=1)
            shaded = int(frame.counts["shade_invocations"])
            rate = shaded / (ms * 1e-3) / 1e6
            print(f"| {name} | {width}x{height} | {k} | {k * k} | {compile_s:.1f} | {ms:.1f} "
                  f"| {shaded:,} | {rate:.2f} |", flush=True)


def convergence(scenes, width, height, ks) -> None:
    print(f"device: {environment()['device']}, jax {jax.__version__}\n")
    print("| scene | resolution | k | 2k | PSNR(k, 2k) dB (LDR) |")
    print("|---|---|---|---|---|")
    pipe = get_pipeline("reference")
    for name in scenes:
        scene = load_lit_scene(name)
        cam = default_camera(scene)
        base = ReferenceConfig(width=width, height=height)
        images = {}
        for k in sorted(set(ks) | {2 * k for k in ks}):
            images[k] = pipe.render(scene, cam, dataclasses.replace(base, k=k)).image
        for k in ks:
            p = float(ldr_psnr(images[k], images[2 * k]))
            print(f"| {name} | {width}x{height} | {k} | {2 * k} | {p:.2f} |", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["spheres"],
                    help=f"built-in scenes or scene files; 'all' = "
                         f"{', '.join(n for n, _ in list_builtin_scenes())}")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--k", type=int, nargs="+", default=[8])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--convergence", action="store_true",
                    help="print PSNR between k and 2k instead of times")
    a = ap.parse_args(argv)
    scenes = [n for n, _ in list_builtin_scenes()] if a.scenes == ["all"] else a.scenes
    if a.convergence:
        convergence(scenes, a.width, a.height, a.k)
    else:
        bench(scenes, a.width, a.height, a.k, a.repeats)


if __name__ == "__main__":
    main()
