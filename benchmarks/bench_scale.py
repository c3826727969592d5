"""Scale: the frames of a camera path one by one, vmapped on one device, and sharded over every
local device (jaxrender.parallel); plus a DACS threshold sweep as a sharded batch of traced
sweep points. Reports ms per frame, compile time apart (first call minus steady median), and
whether the batched frames equal the frame-by-frame ones.

    python benchmarks/bench_scale.py --json scale.json                     # GPU defaults
    JAX_PLATFORMS=cpu XLA_FLAGS=--xla_force_host_platform_device_count=2 \\
        python benchmarks/bench_scale.py --resolution 64x36 --frames 4 --scene spheres --repeats 1
"""

from __future__ import annotations

import argparse
import sys

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender import parallel
from jaxrender.bench.raster import terrain_camera
from jaxrender.bench.report import dump, print_table
from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.timing import environment, time_first_call
from jaxrender.raster import rasterize
from jaxrender.scene.camera_path import frame, orbit
from jaxrender.scene.mesh import terrain_mesh


def _time(call, repeats):
    """(output, steady median in s, first call minus median in s)."""
    r = time_first_call(call, repeats)
    return r["out"], r["median_ms"] / 1e3, r["compile_s"]


def _compare(batched, frames) -> dict:
    b = np.asarray(batched, np.float64)
    f = np.stack([np.asarray(x, np.float64) for x in frames])
    finite = np.isfinite(b) & np.isfinite(f)
    return {"equal_fraction": float(np.mean(b == f)),
            "max_abs_diff": float(np.max(np.abs(np.where(finite, b - f, 0.0)))) if b.size else 0.0}


def _modes(n_dev):
    modes = [("vmap, 1 device", parallel.device_mesh(jax.devices()[:1]))]
    if n_dev > 1:
        modes.append((f"sharded, {n_dev} devices", parallel.device_mesh()))
    return modes


def _raster_ids(scene, camera, cfg):
    positions, faces = scene
    width, height = cfg
    return rasterize(positions, faces, camera, width, height).tri_id


def scale_rows(label, fn, scene, cameras, cfg, n_frames, repeats, chunk, extract):
    """Frame by frame, then batched on one device, then sharded over all of them."""
    single = jax.jit(fn, static_argnums=2)
    cams = [frame(cameras, t) for t in range(n_frames)]

    def loop():
        return [single(scene, c, cfg) for c in cams]

    loop_out, med, comp = _time(loop, repeats)
    base = dict(case=label, frames=n_frames, devices=1, mode="frame by frame")
    rows = [dict(base, ms_per_frame=1e3 * med / n_frames, total_ms=1e3 * med, compile_s=comp)]
    ref = [extract(o) for o in loop_out]
    for mode, mesh in _modes(jax.device_count()):
        try:
            out, med, comp = _time(lambda m=mesh: parallel.render_frames(fn, scene, cameras, cfg,
                                                                     mesh=m, chunk=chunk), repeats)
            rows.append(dict(base, mode=mode, devices=mesh.size, ms_per_frame=1e3 * med / n_frames,
                             total_ms=1e3 * med, compile_s=comp, **_compare(extract(out), ref)))
        except Exception as e:  # noqa: BLE001 - e.g. out of memory for a large batch
            rows.append(dict(base, mode=mode, devices=mesh.size, skipped=f"{type(e).__name__}: {e}"[:200]))
    return rows


def dacs_sweep_rows(scene, camera, width, height, thresholds, repeats, chunk):
    from jaxrender.pipelines import dacs, make_config, program

    cfg = make_config("dacs", width=width, height=height)

    def point(thr, scene, camera):
        # thr is traced under sharded_map, so not dataclasses.replace (its checks need a
        # concrete value): set the traced field as the program does
        return dacs.render(scene, camera, program.join_config(cfg, {"threshold": thr})).image

    thr = jnp.asarray(thresholds, jnp.float32)
    loop_out, med, comp = _time(lambda: [point(t, scene, camera) for t in thr], repeats)
    base = dict(case=f"dacs threshold sweep {width}x{height}", frames=len(thresholds))
    rows = [dict(base, mode="point by point", devices=1, ms_per_frame=1e3 * med / len(thresholds),
                 total_ms=1e3 * med, compile_s=comp)]
    for mode, mesh in _modes(jax.device_count()):
        try:
            out, med, comp = _time(lambda m=mesh: parallel.sharded_map(point, thr, scene, camera,
                                                                   mesh=m, chunk=chunk), repeats)
            rows.append(dict(base, mode=mode, devices=mesh.size,
                             ms_per_frame=1e3 * med / len(thresholds), total_ms=1e3 * med,
                             compile_s=comp, **_compare(out, loop_out)))
        except Exception as e:  # noqa: BLE001
            rows.append(dict(base, mode=mode, devices=mesh.size, skipped=f"{type(e).__name__}: {e}"[:200]))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scene", default="terrain", help="built-in scene for the pipeline cases")
    ap.add_argument("--pipelines", nargs="*", default=["forward", "visbuffer"])
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--frames", type=int, default=16, help="frames of the orbit camera path")
    ap.add_argument("--chunk", type=int, default=8, help="frames per device per call")
    ap.add_argument("--raster-triangles", type=int, default=655_000,
                    help="rasterizer-only case on the benchmark terrain (0: skip)")
    ap.add_argument("--sweep", type=int, default=8, help="DACS threshold sweep points (0: skip)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json")
    a = ap.parse_args(argv)
    width, height = a.resolution
    env = environment()
    print(f"{env}\n{jax.device_count()} device(s): {jax.devices()}\n", flush=True)
    cols = ["case", "mode", "devices", "frames", "ms_per_frame", "total_ms", "compile_s",
            "equal_fraction", "max_abs_diff", "skipped"]
    rows = []

    def emit(new):
        rows.extend(new)
        print_table(new, cols)
        print(flush=True)
        dump(a.json, {"environment": env, "devices": [str(d) for d in jax.devices()], "rows": rows})

    if a.raster_triangles:
        v, f = terrain_mesh(a.raster_triangles)
        base = terrain_camera()
        # a small orbit of the benchmark camera: yaw the eye about the terrain's centre
        eye0 = np.asarray(base.eye, np.float64)
        path = orbit((0.0, 0.0, -5.0), float(np.hypot(eye0[0], eye0[2] + 5.0)), a.frames, 2.0,
                     height=float(eye0[1]), fov_y_deg=55, near=0.5, far=500)
        emit(scale_rows(f"raster {f.shape[0]} tris {width}x{height}", _raster_ids,
                        (jnp.asarray(v), jnp.asarray(f)), path.cameras, (width, height),
                        a.frames, a.repeats, a.chunk, lambda x: x))
    if a.pipelines:
        from jaxrender.pipelines import get_pipeline, make_config
        from jaxrender.scene import default_camera
        from jaxrender.shading import load_lit_scene

        scene = load_lit_scene(a.scene)
        cam = default_camera(scene)
        pos = np.asarray(scene.positions, np.float64)
        c = 0.5 * (pos.min(0) + pos.max(0))  # orbit the scene's bounding-box centre
        eye = np.asarray(cam.eye, np.float64)
        path = orbit(c, max(float(np.hypot(*(eye - c)[[0, 2]])), 1e-3), a.frames, 1.0,
                     height=float(eye[1] - c[1]),
                     fov_y_deg=float(np.rad2deg(cam.fov_y)), near=float(cam.near), far=float(cam.far))
        for name in a.pipelines:
            try:
                cfg = make_config(name, width=width, height=height)
                emit(scale_rows(f"{name} on {a.scene} {width}x{height}", get_pipeline(name).render,
                                scene, path.cameras, cfg, a.frames, a.repeats, a.chunk,
                                lambda fr: fr.image))
            except Exception as e:  # noqa: BLE001
                emit([dict(case=f"{name} on {a.scene}", skipped=f"{type(e).__name__}: {e}"[:200])])
        if a.sweep:
            try:
                emit(dacs_sweep_rows(scene, cam, width, height, np.geomspace(1e-4, 1e-1, a.sweep),
                                     a.repeats, a.chunk))
            except Exception as e:  # noqa: BLE001
                emit([dict(case="dacs threshold sweep", skipped=f"{type(e).__name__}: {e}"[:200])])
    print("## summary\n")
    print_table(rows, cols)
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
