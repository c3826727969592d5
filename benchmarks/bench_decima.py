"""The counts of the decima_foliage study's variants, one frame each, without a reference or
timing: what the Decima claims are computed from (``jaxrender.seeds.decima``).

    python benchmarks/bench_decima.py [--resolution 1920x1080] [--out rows.jsonl]

Prints, per (scene, pipeline), the waves, unfilled lanes, helper lanes, shaded pixels and
vertex work, then the claims (ours beside the talk's). Runs on the default JAX device.
"""

from __future__ import annotations

import argparse
import json
import time

import jax

from jaxrender.parsing import help_summary, parse_resolution
from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.seeds import decima
from jaxrender.study.backend import load_scene
from jaxrender.study.schema import load_study, study_file

KEYS = ("shade_invocations", "waves", "unfilled_lanes", "helper_lanes", "lane_utilization",
        "vertex_invocations", "vertex_bytes", "pixel_command_bytes", "wave_command_bytes")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--resolution", default=None, help="WxH (default: the study's)")
    ap.add_argument("--out", default=None, help="write the rows as JSON Lines here")
    args = ap.parse_args(argv)
    study = load_study(study_file(decima.STUDY))
    w, h = parse_resolution(args.resolution) if args.resolution else study.resolution
    rows = []
    for spec in study.scenes:
        t0 = time.perf_counter()
        scene = load_scene(spec.source, dict(spec.params))
        print(f"{spec.label}: {scene.faces.shape[0]} triangles, {scene.positions.shape[0]} "
              f"vertices (built in {time.perf_counter() - t0:.1f} s)", flush=True)
        for variant in study.variants:
            t0 = time.perf_counter()
            cfg = make_config(variant.type, width=w, height=h, **dict(variant.params))
            f = get_pipeline(variant.type).render(scene, scene.camera, cfg)
            counts = {k: float(f.counts[k]) for k in KEYS if k in f.counts}
            secs = time.perf_counter() - t0
            rows.append({"scene": spec.label, "pipeline": variant.label,
                         "pipeline_type": variant.type, "params": dict(variant.params),
                         "width": w, "height": h, "frame": 0, **counts})
            print(f"  {variant.label:18s} " + "  ".join(
                f"{k}={v:,.0f}" if k != "lane_utilization" else f"{k}={v:.3f}"
                for k, v in counts.items()) + f"  ({secs:.0f} s, compile included)", flush=True)
    conditions = f"{w}x{h}, {jax.devices()[0].platform}, this benchmark"
    for c in decima.claims(rows, conditions):
        r = c.as_row()
        print(f"{r['quantity']}: published {r['published']}, ours "
              f"{'-' if r['ours'] is None else format(r['ours'], '.3f')}: {r['verdict']}"
              + (f" ({r['reason']})" if r["reason"] else ""))
    if args.out:
        with open(args.out, "w") as fh:
            for r in rows:
                fh.write(json.dumps(r) + "\n")


if __name__ == "__main__":
    main()
