"""jaxrender's rasterizer beside its peers, on the same scene, resolution and device:

* jaxrenderer 0.4.0 (PyPI, ``import renderer``), depth only: its README's size (1920x1080,
  about 2.5k triangles) and 640x360 with 10k triangles (the goal: jaxrender at least 150x
  faster; benchmarks/RESULTS.md has the numbers). The goal's ratio (``speedup_vs_jaxrenderer``)
  is taken against jaxrender's ids-and-depth output (``rasterize_depth_clip``), the nearest to
  a depth render, in a frame loop of the compiled program that donates each frame's buffers
  to the next (what ``donate=`` runs); the single call's ratio (previous result kept alive,
  no donation), the same loop through the public entry point and the full VisBuffer are
  printed beside it. Its coverage (depth < 1) is
  compared with jaxrender's; it follows no exact fill rule and culls back faces, so expect
  about 99%.
* the hardware rasterizer through OpenGL/EGL (moderngl, backend "egl"): the same clip-space
  vertices drawn with a pass-through vertex shader, ``gl_PrimitiveID + 1`` written to an R32I
  target, depth test LESS on a 24-bit depth buffer, window origin set to the upper left with
  glClipControl where the driver has it (so that row 0 is the top, as in jaxrender, and the
  fill rule is applied in the same orientation). Timing: glFinish, many draws (clear + draw),
  glFinish, per-draw mean; median of repeats; also the median of single synchronised draws.
  Triangle ids are compared pixel by pixel: raw agreement; agreement with depth ties excluded
  (a differing pixel where GL's triangle has, at the pixel centre, the same window depth as
  jaxrender's within 1e-6: both answers are right); agreement with edge ties excluded as
  well (the centre within one snapping step, 1/256 px, of an edge of either triangle, where
  the two rasterizers' vertex snapping decides); and agreement on pixels away from triangle
  edges (the pixel and its 4 neighbours share one id in both images). Every difference that
  is neither tie is printed with both triangles' depths and edge distances.

The scene is the benchmark terrain (``jaxrender.bench.raster.terrain_clip``, as bench_raster.py
draws). Every peer is optional: a missing package or no GL prints the reason and the rest runs.
The peers live beside this script: peers_jaxrenderer.py, peers_gl.py and peers_agreement.py.

    python benchmarks/bench_peers.py --json peers.json                       # GPU
    JAX_PLATFORMS=cpu python benchmarks/bench_peers.py --tiny                # a CPU smoke run
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from jaxrender.bench.raster import static_args, terrain_clip  # noqa: E402
from jaxrender.bench.report import dump, print_table  # noqa: E402
from jaxrender.errors import UserError  # noqa: E402
from jaxrender.parsing import help_summary, parse_resolution  # noqa: E402
from jaxrender.raster import rasterize_clip, rasterize_depth_clip  # noqa: E402
from jaxrender.raster.rasterize import rasterize_donating, rasterize_program  # noqa: E402
from jaxrender.scene.mesh import terrain_mesh  # noqa: E402
from jaxrender.timing import environment, time_batched, time_interleaved  # noqa: E402
from peers_agreement import compare_ids  # noqa: E402
from peers_gl import gl_available  # noqa: E402
from peers_jaxrenderer import jaxrenderer_available, jaxrenderer_depth  # noqa: E402

JR_CASES = [(1920, 1080, 2_500), (640, 360, 10_000)]
GL_CASES = [(1920, 1080, 2_500), (1920, 1080, 164_000), (1920, 1080, 655_000),
            (1920, 1080, 2_600_000)]
TINY_JR = [(160, 90, 500)]
TINY_GL = [(160, 90, 500), (320, 180, 10_000)]
TIMES = ["resolution", "triangles", "jaxrender_ms", "jaxrender_loop_ms", "jaxrender_depth_ms",
         "jaxrender_depth_loop_ms", "jaxrender_depth_public_loop_ms", "jaxrender_batched_ms",
         "jaxrender_depth_batched_ms", "jaxrender_compile_s", "jaxrenderer_ms",
         "speedup_vs_jaxrenderer", "speedup_single_call", "speedup_full_visbuffer", "gl_ms",
         "gl_sync_ms", "gl_ms_over_jaxrender_ms"]
AGREEMENT = ["resolution", "triangles", "ids_agree", "ids_agree_excl_ties",
             "ids_agree_excl_all_ties", "ids_agree_interior", "interior_fraction",
             "differing_pixels", "depth_ties", "edge_ties", "coverage_only_diffs"]


def cases_arg(text: str) -> list[tuple[int, int, int]]:
    """'1920x1080:2500,640x360:10000' -> [(1920, 1080, 2500), (640, 360, 10000)]"""
    out = []
    for item in filter(None, text.split(",")):
        res, _, n = item.partition(":")
        try:
            out.append((*parse_resolution(res, f"case {item!r}"), int(float(n))))
        except (UserError, ValueError) as e:
            raise argparse.ArgumentTypeError(f"expected WxH:triangles, got {item!r} ({e})") \
                from None
    return out


# ------------------------------------------------------------------ jaxrender


def time_jaxrender(clip, faces, width, height, repeats, draws):
    """For the full VisBuffer and for ids and depth only (``rasterize_depth_clip``: the output
    jaxrenderer's depth render has), median ms of

    * ``jaxrender[_depth]_ms``: single synchronised calls of the compiled program, each
      result kept until the next call returns;
    * ``jaxrender[_depth]_loop_ms``: a frame loop of the same program, each frame donating
      the previous one's buffers (what ``donate=`` runs), as a renderer's loop would;
    * ``jaxrender[_depth]_public_loop_ms``: that loop through the public entry point, whose
      Python checks cost a frame this small about twice their own time (they also delay
      the next dispatch; benchmarks/RESULTS.md);
    * ``jaxrender[_depth]_batched_ms``: ``draws`` calls dispatched back to back with one wait
      (the throughput GL's loop measures).

    All but the last are timed interleaved (``timing.time_interleaved``). Returns the times
    and the VisBuffer of the last single call."""
    out, steps = {}, {}
    static = static_args(faces.shape[0], width, height)
    outputs = (("", True, rasterize_clip), ("_depth", False, rasterize_depth_clip))
    for suffix, bary, entry in outputs:
        t0 = time.perf_counter()
        compiled = rasterize_program.lower(clip, faces, barycentrics=bary, **static).compile()
        out[f"jaxrender{suffix}_compile_s"] = time.perf_counter() - t0
        out[f"jaxrender{suffix}_batched_ms"] = time_batched(
            compiled, clip, faces, calls=draws, repeats=max(3, repeats // 20))
        first = compiled(clip, faces)
        steps[f"jaxrender{suffix}_ms"] = lambda _, c=compiled: c(clip, faces)
        steps[f"jaxrender{suffix}_loop_ms"] = lambda prev, b=bary, f=first: rasterize_donating(
            clip, faces, f if prev is None else prev, barycentrics=b, **static)
        steps[f"jaxrender{suffix}_public_loop_ms"] = lambda prev, e=entry: e(
            clip, faces, width, height, donate=prev)
    medians, last = time_interleaved(steps, repeats)
    return out | medians, last["jaxrender_ms"]


# ------------------------------------------------------------------ one case, peer by peer


def jaxrenderer_columns(row: dict, width, height, n, repeats, ours) -> None:
    """jaxrenderer's depth render of the case into ``row``, and the goal's ratios: depth (and
    ids) against depth, frame after frame; the single call and the full VisBuffer beside it."""
    try:
        v, f = terrain_mesh(n)
        with warnings.catch_warnings():  # jaxtyping warns at every trace
            warnings.simplefilter("ignore")
            t, z = jaxrenderer_depth(v, f, width, height, max(2, repeats // 2))
        row.update(t)
        if ours is not None:
            row["jaxrenderer_coverage_agree"] = float(np.mean((z < 1.0) == (ours >= 0)))
            jr = row["jaxrenderer_ms"]
            row["speedup_vs_jaxrenderer"] = jr / row["jaxrender_depth_loop_ms"]
            row["speedup_single_call"] = jr / row["jaxrender_depth_ms"]
            row["speedup_full_visbuffer"] = jr / row["jaxrender_loop_ms"]
    except Exception as e:  # noqa: BLE001 - a peer that fails is reported, the rest runs
        row["jaxrenderer_error"] = f"{type(e).__name__}: {e}"[:200]


def gl_columns(row: dict, gl, clip, faces, width, height, a, vis) -> None:
    """The GL rasterizer's times for the case into ``row`` and, with our VisBuffer ``vis``,
    the agreement of its triangle ids with ours."""
    try:
        clip_np, faces_np = np.asarray(clip), np.asarray(faces)
        gl.setup(clip_np, faces_np, width, height)
        row.update(gl.time(a.draws, a.repeats))
        theirs = gl.read_ids()
        if vis is not None:
            row.update(compare_ids(np.asarray(vis.tri_id), theirs, vis.depth, clip_np, faces_np,
                                   width, height))
            row["gl_ms_over_jaxrender_ms"] = row["gl_ms"] / row["jaxrender_ms"]
        gl.release()
    except Exception as e:  # noqa: BLE001
        row["gl_error"] = f"{type(e).__name__}: {e}"[:200]


def case_row(case, a, jr_cases, gl_cases, gl) -> dict:
    """Every measurement of one (width, height, triangles) case: jaxrender always, each peer
    where it runs this case (``jr_cases`` None: jaxrenderer is skipped)."""
    width, height, n = case
    clip, faces = terrain_clip(n, width, height)
    row = dict(resolution=f"{width}x{height}", triangles=int(faces.shape[0]))
    try:
        t, vis = time_jaxrender(clip, faces, width, height, a.jaxrender_repeats, a.draws)
        row.update(t)
    except Exception as e:  # noqa: BLE001
        row["jaxrender_error"] = f"{type(e).__name__}: {e}"[:200]
        vis = None
    if jr_cases is not None and case in jr_cases:
        jaxrenderer_columns(row, width, height, n, a.repeats,
                            None if vis is None else np.asarray(vis.tri_id))
    if gl is not None and case in gl_cases:
        gl_columns(row, gl, clip, faces, width, height, a, vis)
    return row


# ------------------------------------------------------------------ main


def parse_args(argv=None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=help_summary(__doc__),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jaxrenderer-cases", type=cases_arg, help="WxH:triangles,... (default: "
                    "1920x1080:2500,640x360:10000)")
    ap.add_argument("--gl-cases", type=cases_arg, help="WxH:triangles,... (default: 1920x1080 "
                    "at 2500, 164000, 655000, 2600000)")
    ap.add_argument("--tiny", action="store_true", help="CPU smoke sizes")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--draws", type=int, default=50, help="draws per timed GL/jaxrender batch")
    ap.add_argument("--jaxrender-repeats", type=int, default=300,
                    help="single synchronised jaxrender calls timed per case")
    ap.add_argument("--no-jaxrenderer", action="store_true")
    ap.add_argument("--no-gl", action="store_true")
    ap.add_argument("--json")
    return ap.parse_args(argv)


def find_peers(a, payload: dict):
    """(jaxrenderer's reason to skip or None, the GL rasterizer or None); each reason to skip
    is printed and kept in ``payload["skipped"]``, GL's driver in ``payload["gl"]``."""
    jr_reason = "--no-jaxrenderer" if a.no_jaxrenderer else jaxrenderer_available()
    if jr_reason:
        payload["skipped"]["jaxrenderer"] = jr_reason
        print(f"skip jaxrenderer: {jr_reason}", flush=True)
    gl, gl_reason = (None, "--no-gl") if a.no_gl else gl_available()
    if gl_reason:
        payload["skipped"]["gl"] = gl_reason
        print(f"skip OpenGL: {gl_reason}", flush=True)
    else:
        payload["gl"] = gl.info
        print(f"OpenGL: {gl.info}", flush=True)
    return jr_reason, gl


def main(argv=None) -> int:
    a = parse_args(argv)
    jr_cases = a.jaxrenderer_cases or (TINY_JR if a.tiny else JR_CASES)
    gl_cases = a.gl_cases or (TINY_GL if a.tiny else GL_CASES)
    env = environment()
    print(env, flush=True)
    rows = []
    payload = {"environment": env, "skipped": {}, "rows": rows}
    jr_reason, gl = find_peers(a, payload)
    cases = sorted(set(([] if jr_reason else jr_cases) + ([] if gl is None else gl_cases)),
                   key=lambda c: (c[2], c[0]))
    if not cases:  # still time jaxrender alone, so the script says something useful
        cases = sorted(set(jr_cases + gl_cases), key=lambda c: (c[2], c[0]))
    for case in cases:
        rows.append(case_row(case, a, None if jr_reason else jr_cases, gl_cases, gl))
        print(rows[-1], flush=True)
        dump(a.json, payload)
    print("\n## jaxrender vs jaxrenderer 0.4.0 (depth only) and OpenGL (ids), median ms\n")
    print_table(rows, TIMES)
    print("\n## triangle-id agreement with OpenGL\n")
    print_table([r for r in rows if "ids_agree" in r], AGREEMENT)
    if payload["skipped"]:
        print(f"\nskipped: {payload['skipped']}")
    dump(a.json, payload)
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
