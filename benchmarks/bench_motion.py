"""Motion benchmark: the cost per frame of the motion-vector output and of the TAA resolve,
variants side by side in one run.

    python benchmarks/bench_motion.py                        # 1920x1080 (the GPU figures)
    python benchmarks/bench_motion.py --size 64x36 --frames 4 --repeats 2   # CPU smoke run

Rows:
- ``visibility``: the visibility pass alone, and with motion vectors and the previous depth
  (``pipelines.visibility(previous=...)``); their difference is the motion-vector output's cost
  (target <= 0.2 ms at 1920x1080 on the GPU).
- ``motion_vectors``: the motion-vector stage alone on a resolved visibility buffer.
- ``taa_resolve``: the temporal resolve alone (``pipelines.taa.resolve``: reprojection,
  disocclusion test, history sample, neighbourhood bound, blend) on given buffers, for each
  history filter x bound (target <= 0.3 ms).
- ``deferred`` / ``deferred+taa``: a whole sequence per frame, without and with TAA (TAA adds
  the jitter, its own visibility pass with motion vectors and the resolve).
"""

from __future__ import annotations

import argparse
import os
import sys
from functools import partial

import jax
import jax.numpy as jnp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from jaxrender.bench.report import dump, print_table  # noqa: E402
from jaxrender.timing import environment, time_compiled  # noqa: E402

from jaxrender.pipelines import get_pipeline, make_config  # noqa: E402
from jaxrender.pipelines.base import PipelineConfig  # noqa: E402
from jaxrender.pipelines.taa import History, resolve  # noqa: E402
from jaxrender.pipelines.visibility import Previous, visibility  # noqa: E402
from jaxrender.raster.motion import motion_vectors  # noqa: E402
from jaxrender.scene.animation import pose, positions_at  # noqa: E402
from jaxrender.scene.camera_path import pan  # noqa: E402
from jaxrender.shading import load_lit_scene  # noqa: E402


def _size(text: str) -> tuple[int, int]:
    w, h = text.lower().split("x")
    return int(w), int(h)


def bench_visibility(scene, path, cfg, repeats):
    cam, prev = jax.tree.map(lambda a: a[1], path.cameras), jax.tree.map(lambda a: a[0],
                                                                         path.cameras)
    posed = pose(scene, 1)
    prev_pos = positions_at(scene, 0)

    def plain(sc, c):
        v = visibility(sc, c, cfg)
        return v.tri_id, v.depth

    def with_motion(sc, c, pp, pc):
        v = visibility(sc, c, cfg, previous=Previous(pp, pc))
        return v.tri_id, v.depth, v.motion, v.prev_depth

    def stage(tri, bary, sc, c, pp, pc):
        return motion_vectors(tri, bary, sc.faces, sc.positions, c, pp, pc, cfg.width,
                              cfg.height)

    rows = []
    r = time_compiled(plain, posed, cam, repeats=repeats)
    r.pop("out")
    rows.append(dict(stage="visibility", variant="plain", **r))
    r = time_compiled(with_motion, posed, cam, prev_pos, prev, repeats=repeats)
    r.pop("out")
    rows.append(dict(stage="visibility", variant="+motion vectors", **r))
    vis = jax.jit(lambda sc, c: visibility(sc, c, cfg))(posed, cam)
    r = time_compiled(stage, vis.tri_id, vis.bary, posed, cam, prev_pos, prev, repeats=repeats)
    r.pop("out")
    rows.append(dict(stage="motion_vectors", variant="alone", **r))
    return rows, vis, (posed, cam, prev_pos, prev)


def _resolved(current, vis, objects, hist, camera, *, cfg):
    return resolve(current, vis, objects, hist, camera, cfg).image


def bench_resolve(scene, path, cfg_w, cfg_h, inputs, repeats):
    posed, cam, prev_pos, prev = inputs
    vis_cfg = PipelineConfig(width=cfg_w, height=cfg_h)
    vis = jax.jit(lambda sc, c, pp, pc: visibility(sc, c, vis_cfg, previous=Previous(pp, pc)))(
        posed, cam, prev_pos, prev)
    objects = jnp.where(vis.tri_id >= 0, posed.tri_object[jnp.maximum(vis.tri_id, 0)], -1)
    image = jnp.full((cfg_h, cfg_w, 3), 0.5, jnp.float32)
    hist = History(image, vis.depth, objects, prev, jnp.asarray(True))
    rows = []
    for history in ("bilinear", "catmull_rom"):
        for clip in ("clamp", "variance"):
            cfg = make_config("deferred", width=cfg_w, height=cfg_h, taa=True,
                              taa_history=history, taa_clip=clip)
            r = time_compiled(partial(_resolved, cfg=cfg), image, vis, objects, hist, cam,
                              repeats=repeats)
            r.pop("out")
            rows.append(dict(stage="taa_resolve", variant=f"{history}+{clip}", **r))
    return rows


def bench_sequences(scene, path, w, h, repeats):
    pipe = get_pipeline("deferred")
    rows = []
    n = len(path)
    for label, kw in (("deferred", {}), ("deferred+taa", {"taa": True})):
        cfg = make_config("deferred", width=w, height=h, **kw)
        fn = jax.jit(lambda sc, cams, cfg=cfg: pipe.render_sequence(sc, cams, cfg).image)
        r = time_compiled(fn, scene, path.cameras, repeats=repeats)
        r.pop("out")
        per = {k: v / n for k, v in r.items() if k in ("median_ms", "min_ms", "max_ms")}
        rows.append(dict(r, stage="sequence per frame", variant=label, frames=n, **per))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--scene", default="spheres_spin")
    ap.add_argument("--frames", type=int, default=8, help="frames of the sequence rows")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--no-sequences", action="store_true", help="skip the whole-sequence rows")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args(argv)
    w, h = _size(args.size)
    scene = load_lit_scene(args.scene)
    path = pan(scene.camera, max(args.frames, 2), 2.0, h)
    cfg = PipelineConfig(width=w, height=h)
    rows, _, inputs = bench_visibility(scene, path, cfg, args.repeats)
    rows += bench_resolve(scene, path, w, h, inputs, args.repeats)
    if not args.no_sequences:
        rows += bench_sequences(scene, path, w, h, args.repeats)
    for r in rows:
        r.update(resolution=f"{w}x{h}", scene=args.scene)
    print_table(rows, ["resolution", "scene", "stage", "variant", "median_ms", "min_ms",
                       "compile_s"])
    dump(args.json, {"environment": environment(), "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
