"""Each registered pipeline's frame time on each built-in scene (compile apart), with the
shading counts beside it. A (scene, pipeline) that fails is kept as a row with its reason."""

from __future__ import annotations

import time

from jaxrender.parsing import parse_spec
from jaxrender.timing import sample_stats, time_call

# Scenes as "name" or "name:key=value,key=value" (TOML values); the 100k-triangle target scene
# comes second, so that a time budget reaches it.
TARGET_SCENE = "many_small:n_triangles=100000,point_lights=4"
COUNT_COLUMNS = ("shade_invocations", "helper_lanes", "overshading", "waves", "lane_utilization",
                 "bytes_intermediate", "overflow")


def default_scene_specs() -> list[str]:
    from jaxrender.scene import list_builtin_scenes

    first = ["terrain", TARGET_SCENE, "room", "foliage"]  # studies/performance.toml's, first
    names = [n for n, _ in list_builtin_scenes()]
    return first + [n for n in names if n not in first]


PRESETS = {"forward": ["forward:z_prepass=true"]}  # as configs/pipelines/forward_prepass.toml


def default_pipeline_specs() -> list[str]:
    """Every registered pipeline with its defaults, plus the presets the studies use."""
    from jaxrender.pipelines import list_pipelines

    order = ["forward", "deferred", "visbuffer", "checkerboard", "dacs", "object_space"]
    names = sorted((p.name for p in list_pipelines()),  # the reference (16 spp) last
                   key=lambda n: (n == "reference", order.index(n) if n in order else len(order), n))
    return [s for n in names for s in [n] + PRESETS.get(n, [])]


def time_pipelines(scene_specs, pipeline_specs, width: int, height: int, *, repeats: int = 5,
                   deadline: float | None = None):
    """Yield one row per (scene, pipeline); rows past ``deadline`` (time.monotonic) are skipped."""
    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.scene import default_camera
    from jaxrender.shading import load_lit_scene
    from jaxrender.timing import compile_program

    for scene_spec in scene_specs:
        base = dict(scene=scene_spec, resolution=f"{width}x{height}")
        if deadline is not None and time.monotonic() > deadline:
            yield dict(base, skipped="time budget spent")
            continue
        try:
            name, params = parse_spec(scene_spec, "scene")
            t0 = time.perf_counter()
            scene = load_lit_scene(name, **params)
            camera = default_camera(scene)
            base["load_s"] = time.perf_counter() - t0
            base["scene_triangles"] = int(scene.faces.shape[0]) if hasattr(scene, "faces") else None
        except Exception as e:  # noqa: BLE001 - a benchmark reports and goes on
            yield dict(base, skipped=f"scene: {type(e).__name__}: {e}"[:200])
            continue
        for pipe_spec in pipeline_specs:
            row = dict(base, pipeline=pipe_spec)
            if deadline is not None and time.monotonic() > deadline:
                yield dict(row, skipped="time budget spent")
                continue
            try:
                pname, pparams = parse_spec(pipe_spec, "pipeline")
                pipe = get_pipeline(pname)
                cfg = make_config(pname, width=width, height=height, **pparams)
                comp = compile_program(pipe, scene, camera, cfg)
                frame, _, samples = time_call(comp.call, scene, camera, repeats=repeats,
                                              warmup=1)
                row.update(sample_stats(samples), compile_s=comp.compile_ms / 1e3)
                counts = getattr(frame, "counts", None) or {}
                for k in COUNT_COLUMNS:
                    if k in counts:
                        row[k] = float(counts[k])
            except Exception as e:  # noqa: BLE001
                row["skipped"] = f"{type(e).__name__}: {e}"[:200]
            yield row


COLUMNS = ["scene", "pipeline", "resolution", "median_ms", "min_ms", "compile_s",
           "shade_invocations", "overshading", "skipped"]
