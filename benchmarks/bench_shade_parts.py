"""What each effect of a scene's shader costs in one launch of ``shade()``, and what the
compiled launch writes between its kernels.

    python benchmarks/bench_shade_parts.py --scenes room --hlo hlo/   # also the compiled HLO

Rasterizes each scene's default view, compacts its covered pixels and times one launch of
``surface_points`` and ``shade()`` over all of them: with the scene's effects, with each one
(textures, normal map, specular lobes, shadows) turned off alone, and with all of them off.
Each row also gives XLA's cost analysis per point (flops, bytes accessed) and, from the
optimized program, its kernels (top-level instructions that write) and the bytes per point
that they write in point-sized arrays: a fused shader writes a few, a shader split into many
kernels writes its intermediates to memory and reads them back. ``--hlo`` keeps each
optimized program's text.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from bench_cost_layers import covered_points
from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.scene import default_camera
from jaxrender.shading import load_lit_scene, shade, surface_points
from jaxrender.timing import device_description, time_call

PARTS = ("textures", "normal_map", "specular", "shadows")
# A top-level instruction: its name, its result (one array or a tuple of them), its opcode.
INSTRUCTION = re.compile(r"^\s*(?:ROOT )?%\S+ = (\(.*?\)|\w+\[[\d,]*\]\S*) ([\w-]+)\(")
ARRAY = re.compile(r"(\w+)\[([\d,]*)\]")
# Not kernels and not stores: arguments, constants, views of a result, pieces of a tuple.
NOT_WRITTEN = ("parameter", "constant", "bitcast", "get-tuple-element", "tuple")
BYTES = {"f32": 4, "s32": 4, "u32": 4, "pred": 1, "s8": 1, "u8": 1, "f16": 2, "bf16": 2}


def variants(effects) -> dict:
    """label -> the effects' fields to change: the scene's own, each part off, all off."""
    on = [p for p in PARTS if getattr(effects, p)]
    out = {"all on": {}}
    out.update({f"no {p}": {p: False} for p in on})
    if len(on) > 1:
        out["all off"] = {p: False for p in on}
    return out


def point_sized_writes(hlo: str, n: int) -> tuple[int, float]:
    """(kernels: top-level instructions that write, bytes a point they write in arrays of n
    leading entries): a multi-output fusion's tuple counted element by element."""
    entry = hlo.split("\nENTRY", 1)[1]
    count, written = 0, 0
    for line in entry.splitlines()[1:]:
        m = INSTRUCTION.match(line)
        if not m or m.group(2) in NOT_WRITTEN:
            continue
        count += 1
        for dtype, dims in ARRAY.findall(m.group(1)):
            shape = [int(d) for d in dims.split(",") if d]
            if shape and shape[0] == n:
                written += BYTES.get(dtype, 4) * int(np.prod(shape))
    return count, written / n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["room"])
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--out", default="shade_parts.jsonl")
    ap.add_argument("--hlo", default="", help="a folder for each optimized program's text")
    ap.add_argument("--label", default="", help="a name for this tree in the rows")
    ap.add_argument("--own-effects", action="store_true",
                    help="only each scene's own effects (no part turned off)")
    a = ap.parse_args(argv)
    w, h = a.resolution
    print(f"device: {device_description()}, jax {jax.__version__}, {a.label}", flush=True)
    print("| scene | effects | ms | flops/pt | bytes/pt accessed | kernels | "
          "bytes/pt written |")
    print("|---|---|---:|---:|---:|---:|---:|", flush=True)
    for name in a.scenes:
        base = load_lit_scene(name)
        camera = default_camera(base)
        pts = tuple(jnp.asarray(p) for p in covered_points(base, camera, w, h))
        n = int(pts[0].shape[0])
        chosen = variants(base.effects)
        if a.own_effects:
            chosen = {"all on": chosen["all on"]}
        for label, change in chosen.items():
            scene = dataclasses.replace(
                base, effects=dataclasses.replace(base.effects, **change))
            fn = jax.jit(lambda s, c, p: shade(surface_points(s, c, *p), s))
            compiled = fn.lower(scene, camera, pts).compile()
            _, ms, _ = time_call(compiled, scene, camera, pts, repeats=a.repeats, warmup=2)
            cost = compiled.cost_analysis()
            cost = (cost[0] if isinstance(cost, list) else cost) or {}
            hlo = compiled.as_text()
            kernels, written = point_sized_writes(hlo, n)
            if a.hlo:
                Path(a.hlo).mkdir(parents=True, exist_ok=True)
                Path(a.hlo, f"{name}_{label.replace(' ', '_')}.hlo.txt").write_text(hlo)
            row = dict(scene=name, effects=label, label=a.label, points=n, ms=ms,
                       flops_per_point=cost.get("flops", 0.0) / n,
                       bytes_per_point=cost.get("bytes accessed", 0.0) / n,
                       kernels=kernels, written_per_point=written)
            with open(a.out, "a") as f:
                f.write(json.dumps(row) + "\n")
            print(f"| {name} | {label} | {ms:.3f} | {row['flops_per_point']:.0f} | "
                  f"{row['bytes_per_point']:.0f} | {kernels} | {written:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
