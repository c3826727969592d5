"""Per-frame time of every pipeline inside a sequence (``render_sequence``: one program, a
``lax.scan`` of the pipeline's step over the path) against single-frame calls (``render``'s
program called once per camera), on the same cameras.

    python benchmarks/bench_sequence.py --scenes terrain foliage --resolution 1920x1080 \
        --frames 60 --rounds 5

Programs are compiled ahead of time (in threads: XLA compiles outside the GIL), all of them
before anything is timed. Each round times the whole sequence once and then the single-frame program once on
every camera of the path, so the two are interleaved on the noisy lent machine; the table
gives the medians over rounds of (sequence ms / frames) and of the per-round mean single call,
and their ratio (sequence per frame / single: below 1 the sequence is faster).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor, wait
from pathlib import Path

import jax
import numpy as np

# This checkout's package, unless PYTHONPATH names a tree of its own: the side-by-side runs
# (`PYTHONPATH=.v/v0 python benchmarks/bench_sequence.py`) must time the tree they name.
if not any((Path(p) / "jaxrender").is_dir()
           for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from jaxrender.bench.report import print_table  # noqa: E402
from jaxrender.parsing import help_summary, parse_spec, resolution_arg  # noqa: E402
from jaxrender.timing import environment, time_call  # noqa: E402
from jaxrender.pipelines import list_pipelines, make_config, program  # noqa: E402
from jaxrender.scene.camera_path import pan  # noqa: E402
from jaxrender.shading import load_lit_scene  # noqa: E402


def _compile_both(pipe, scene, path, cfg, single=True, outputs="all"):
    # An older tree (PYTHONPATH=.v/...) knows no `outputs`: it is passed only when not "all".
    kw = {} if outputs == "all" else {"outputs": outputs}
    seq, seq_ms = program.compile(pipe, scene, path, cfg, sequence=True, **kw)
    if not single:
        return seq, None, seq_ms / 1e3, None
    one, one_ms = program.compile(pipe, scene, _camera(path, 0), cfg, **kw)
    return seq, one, seq_ms / 1e3, one_ms / 1e3


def _camera(path, i):
    return jax.tree_util.tree_map(lambda x: x[i], path)


def _time(fn, *args) -> float:
    return time_call(fn, *args, repeats=1)[1]


def _checksum(frames) -> dict:
    """The sequence's image sum (float64 on the host) and total shading invocations."""
    counts = frames.counts or {}
    out = {"image_sum": float(np.asarray(frames.image, np.float64).sum())}
    if "shade_invocations" in counts:
        out["invocations"] = int(np.asarray(counts["shade_invocations"]).sum())
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["terrain", "foliage"])
    ap.add_argument("--pipelines", nargs="+", default=None,
                    help="names or 'name:key=value,...' config variants; default: every "
                         "registered pipeline")
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--pixels-per-frame", type=float, default=1.0)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--json", default=None, help="write the rows here")
    ap.add_argument("--no-single", action="store_true",
                    help="time the sequence only (how studies time a frame), not single calls")
    ap.add_argument("--checksum", action="store_true",
                    help="add each sequence's image sum and shading count to its row, to show "
                         "that two variants (XLA flags, trees) rendered the same frames")
    ap.add_argument("--outputs", choices=("images", "all"), default=None,
                    help="what the timed programs return: the images alone (the default; XLA "
                         "drops the counts' and views' work), or the counts and views too (as "
                         "before the twenty-fourth session; the default for an older tree)")
    a = ap.parse_args(argv)
    a.outputs = a.outputs or ("images" if hasattr(program, "OUTPUTS") else "all")
    if a.checksum and a.outputs == "images":
        ap.error("--checksum sums each sequence's shading count, which an images-only program "
                 "does not return: add --outputs all")
    w, h = a.resolution
    names = a.pipelines or [p.name for p in list_pipelines()]
    env = environment()
    print(f"# {env}", flush=True)
    jobs = {}
    with ThreadPoolExecutor(max_workers=4) as pool:
        for sname in a.scenes:
            scene = load_lit_scene(sname)
            cams = pan(scene.camera, a.frames, a.pixels_per_frame, h).cameras
            path = cams  # batched: stacked once, outside the timed calls
            for name in names:
                base, params = parse_spec(name, "--pipelines")
                pipe = next(p for p in list_pipelines() if p.name == base)
                cfg = make_config(base, width=w, height=h, **params)
                jobs[sname, name] = (scene, path, pool.submit(_compile_both, pipe, scene, path,
                                                               cfg, not a.no_single, a.outputs))
        wait([fut for _, _, fut in jobs.values()])  # no compile thread competes with a timing
        rows = []
        for (sname, name), (scene, path, fut) in jobs.items():
            try:
                seq, one, seq_c, one_c = fut.result()
                frames = jax.block_until_ready(seq(scene, path))  # warm-up
                singles = [_camera(path, i) for i in range(a.frames)] if one else []
                if one:
                    jax.block_until_ready(one(scene, singles[0]))
                seq_pf, single = [], []
                for _ in range(a.rounds):
                    seq_pf.append(_time(seq, scene, path) / a.frames)
                    if one:
                        single.append(statistics.mean(_time(one, scene, c) for c in singles))
                s = statistics.median(seq_pf)
                o = statistics.median(single) if one else None
                rows.append({"scene": sname, "pipeline": name, "sequence_ms_per_frame": s,
                             "single_ms": o, "ratio": s / o if o else None,
                             "compile_seq_s": seq_c, "compile_single_s": one_c})
                if a.checksum:
                    rows[-1].update(_checksum(frames))
            except Exception as e:  # noqa: BLE001 - a benchmark reports and goes on
                rows.append({"scene": sname, "pipeline": name,
                             "error": f"{type(e).__name__}: {e}"[:160]})
            print(json.dumps(rows[-1]), flush=True)
    print(f"\n{w}x{h}, {a.frames}-frame pan ({a.pixels_per_frame} px/frame), outputs "
          f"{a.outputs}, {a.rounds} rounds; {env['device']}, jax {env['jax_version']}, "
          f"{time.strftime('%Y-%m-%d')}\n")
    print_table(rows, ["scene", "pipeline", "sequence_ms_per_frame", "single_ms", "ratio",
                       "compile_seq_s", "compile_single_s", "error"])
    if a.json:
        Path(a.json).write_text(json.dumps({"env": env, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
