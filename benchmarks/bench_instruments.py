"""What a frame's counts and views cost: each pipeline's sequence program timed with all its
outputs (as studies and ``bench_sequence.py`` timed it before the twenty-fourth session) and
with its images alone (as they time it now, ``program.OUTPUTS``).

    python benchmarks/bench_instruments.py --scenes thin foliage room --resolution 1920x1080

Without the counts and the auxiliary views among its outputs, XLA drops every computation
that only they read (object space's finest-level marking and needed shadels, DACS's warp
simulation, ...), so 1 - (images only / all) is the share of a frame that is the study's
instruments rather than the architecture's work. XLA may also fuse the smaller program
differently (on the CPU some ratios came out above 1), so a ratio bounds that share only
where it is well below 1. The all-outputs program's first run is checked for overflow (a
frame that dropped work is not timed), the two programs are alternated, and each row gives
the smallest median over the rounds.
"""

from __future__ import annotations

import argparse
import json

import jax

from jaxrender import camera_path
from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.pipelines import make_config, program
from jaxrender.pipelines.registry import REGISTRY
from jaxrender.scene import default_camera
from jaxrender.shading import load_lit_scene
from jaxrender.timing import device_description, time_call

PIPELINES = ("deferred", "checkerboard", "visbuffer", "dacs", "forward", "object_space", "tads")


def programs(name: str, scene, path, width: int, height: int):
    """(all outputs, images only) compiled, and their arguments; raises PipelineOverflow
    if the sequence overflows a capacity."""
    pipe, cfg = REGISTRY[name], make_config(name, width=width, height=height)
    compiled = []
    for outputs in ("all", "images"):  # the same dynamic arguments: the static ones differ
        fixed, args, _ = program.arguments(pipe, scene, path, cfg, sequence=True,
                                           outputs=outputs)
        compiled.append(jax.jit(program.unjitted(fixed)).lower(*args).compile())
    every, images = compiled
    program.check_overflow(pipe, cfg, every(*args))
    return every, images, args


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["thin", "foliage", "room"])
    ap.add_argument("--pipelines", nargs="+", default=list(PIPELINES))
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default="instruments.jsonl")
    a = ap.parse_args(argv)
    w, h = a.resolution
    print(f"device: {device_description()}, jax {jax.__version__}; {a.frames}-frame pans, "
          f"ms a frame, the smallest of {a.rounds} medians of {a.repeats}", flush=True)
    print("| scene | pipeline | all outputs | images only | images only / all |")
    print("|---|---|---:|---:|---:|", flush=True)
    for scene_name in a.scenes:
        scene = load_lit_scene(scene_name)
        path = camera_path.pan(default_camera(scene), a.frames, pixels_per_frame=1.0, height=h)
        for name in a.pipelines:
            try:
                every, images, args = programs(name, scene, path, w, h)
            except (ValueError, program.PipelineOverflow) as e:  # TADS on glass; an overflow
                print(f"| {scene_name} | {name} | refused: {e} | | |", flush=True)
                continue
            ms = {"all": [], "images": []}
            for _ in range(a.rounds):
                for label, call in (("all", every), ("images", images)):
                    ms[label].append(time_call(call, *args, repeats=a.repeats, warmup=1)[1]
                                     / a.frames)
            t_all, t_img = min(ms["all"]), min(ms["images"])
            row = dict(scene=scene_name, pipeline=name, width=w, height=h, frames=a.frames,
                       ms_all=t_all, ms_images=t_img, ratio=t_img / t_all,
                       device=device_description(), jax=jax.__version__)
            with open(a.out, "a") as f:
                f.write(json.dumps(row) + "\n")
            print(f"| {scene_name} | {name} | {t_all:.3f} | {t_img:.3f} | {t_img / t_all:.3f} |",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
