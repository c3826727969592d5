"""The shared shader alone: a screen of surface points (interpolation and ``shade()``), per scene.

    python benchmarks/bench_shader.py --scenes room foliage --resolution 1920x1080
    python benchmarks/bench_shader.py --scenes room --hlo-dir /tmp/hlo   # the compiled program

Rasterizes each scene's default view once, then profiles the program that every pipeline runs
per shaded batch: ``surface_points`` of every covered pixel and ``shade()`` on them, in one
launch. Prints the wall time, the summed kernel time and the kernels launched
(``profile_kernels.profile_call``), and the number of fusions in the optimized HLO. Run it from
two trees (``PYTHONPATH=.before``) to compare shader implementations side by side.
"""

from __future__ import annotations

import argparse
import os
import re
import sys

import jax
import jax.numpy as jnp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from profile_kernels import profile_call  # noqa: E402

from jaxrender.parsing import help_summary, parse_spec, resolution_arg  # noqa: E402
from jaxrender.pipelines import make_config  # noqa: E402
from jaxrender.pipelines.visibility import visibility  # noqa: E402
from jaxrender.scene import default_camera  # noqa: E402
from jaxrender.shading import load_lit_scene, shade, surface_points  # noqa: E402
from jaxrender.timing import device_description  # noqa: E402


def screen_shader(scene, camera, vis):
    """float32[P, 3]: every pixel's surface point shaded (empty pixels black), one launch."""
    flat = lambda a: a.reshape((-1,) + a.shape[2:])  # noqa: E731
    pts = surface_points(scene, camera, flat(vis.tri_id), flat(vis.bary), flat(vis.dbary_dx),
                         flat(vis.dbary_dy))
    return shade(pts, scene)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["room"])
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--calls", type=int, default=5)
    ap.add_argument("--top", type=int, default=8)
    ap.add_argument("--hlo-dir", help="write each scene's optimized HLO here")
    ap.add_argument("--label", default="", help="a name for this tree in the output")
    args = ap.parse_args(argv)
    w, h = args.resolution
    print(f"device: {device_description()}, jax {jax.__version__}")
    cfg = make_config("deferred", width=w, height=h)
    for spec in args.scenes:
        name, params = parse_spec(spec, "--scenes")
        sc = load_lit_scene(name, **params)
        cam = default_camera(sc)
        vis = jax.jit(lambda s, c: visibility(s, c, cfg))(sc, cam)
        fn = jax.jit(screen_shader)
        text = fn.lower(sc, cam, vis).compile().as_text()
        fusions = len(re.findall(r"^\s*(?:ROOT )?%?[\w.\-]+ = \S+ fusion\(", text, re.M))
        if args.hlo_dir:
            os.makedirs(args.hlo_dir, exist_ok=True)
            with open(os.path.join(args.hlo_dir, f"shade_{name}{args.label}.hlo.txt"), "w") as f:
                f.write(text)
        r = profile_call(fn, sc, cam, vis, calls=args.calls, top=args.top,
                         label=f"shader {args.label} {spec} {w}x{h}")
        covered = int(jnp.sum(vis.tri_id >= 0))
        print(f"RESULT {args.label} {spec}: {r['kernel_ms']:.3f} ms of kernels, "
              f"{r['launches']:.0f} launches, {fusions} fusions in the HLO, {covered} points, "
              f"{r['kernel_ms'] * 1e6 / max(covered, 1):.2f} ns/point")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
