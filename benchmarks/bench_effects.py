"""Time shade() with each effect on vs off on one scene's visible points (honest timing:
warm-up, block_until_ready, median of repeats, compile time apart). Prints a markdown table.

    python benchmarks/bench_effects.py --scene room --width 256 --height 192 --repeats 10
"""

from __future__ import annotations

import argparse
import platform

import jax

from jaxrender.parsing import help_summary
from jaxrender.raster import rasterize
from jaxrender.scene import load_scene
from jaxrender.shading import shade, surface_points
from jaxrender.timing import device_description, time_first_call

VARIANTS = [  # (label, changes for "on", changes for "off")
    ("textures", {"textures": True}, {"textures": False}),
    ("normal_map", {"normal_map": True}, {"normal_map": False}),
    ("specular", {"specular": True}, {"specular": False}),
    ("shadows", {"shadows": True}, {"shadows": False}),
    ("emissive", {"emissive": True}, {"emissive": False}),
    ("toksvig", {"toksvig": True}, {"toksvig": False}),
    ("aniso_taps 4 vs 1", {"aniso_taps": 4}, {"aniso_taps": 1}),
    ("shader_cost 4 vs 0", {"shader_cost": 4}, {"shader_cost": 0}),
]


def timed(fn, *args, repeats):
    """(median s, compile s: the first call's time minus the median)."""
    r = time_first_call(lambda: fn(*args), repeats)
    return r["median_ms"] / 1e3, r["compile_s"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scene", default="room")
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=192)
    ap.add_argument("--repeats", type=int, default=10)
    args = ap.parse_args(argv)

    scene = load_scene(args.scene, effects={"shadow_map_size": 512})
    if scene.shadow is None:
        from jaxrender.shading import with_shadow_map
        scene = with_shadow_map(scene)
    cam = scene.camera
    vis = rasterize(scene.positions, scene.faces, cam, args.width, args.height)
    pts = jax.jit(surface_points)(scene, cam, vis.tri_id.reshape(-1), vis.bary.reshape(-1, 3),
                                  vis.dbary_dx.reshape(-1, 3), vis.dbary_dy.reshape(-1, 3))
    n = int(pts.valid.sum())
    pts = jax.tree_util.tree_map(lambda a: a[pts.valid], pts)  # a compacted work list
    base = scene.effects
    print(f"device: {device_description()} ({platform.node()}), scene {scene.name}, "
          f"{n} shaded points ({args.width}x{args.height}), median of {args.repeats}\n")
    print("| effect | on (ms) | off (ms) | on/off | compile on (s) | compile off (s) |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, on, off in VARIANTS:
        res = []
        for changes in (on, off):
            eff = base.replace(**changes)
            fn = jax.jit(lambda p, s, eff=eff: shade(p, s, eff))
            res.append(timed(fn, pts, scene, repeats=args.repeats))
        (t_on, c_on), (t_off, c_off) = res
        print(f"| {label} | {t_on * 1e3:.2f} | {t_off * 1e3:.2f} | {t_on / t_off:.2f} | "
              f"{c_on:.2f} | {c_off:.2f} |")


if __name__ == "__main__":
    main()
