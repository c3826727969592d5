"""Each registered pipeline's frame time on each built-in scene (compile apart), with the
shading counts beside it. A (scene, pipeline) that fails is kept as a row with its reason.

The timed program returns the image alone (``program.OUTPUTS``), so XLA drops the work only
the counts and views need; the counts come from one call of the instrumented program."""

from __future__ import annotations

import statistics
import time
from concurrent.futures import ThreadPoolExecutor, wait

from jaxrender.parsing import parse_spec
from jaxrender.timing import block

# Scenes as "name" or "name:key=value,key=value" (TOML values); the 100k-triangle target scene
# comes second, beside the scenes of studies/performance.toml.
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


def time_row(call, repeats: int, budget_s: float | None = None) -> dict:
    """A warm-up call, then up to ``repeats`` timed calls, fewer once ``budget_s`` seconds of
    them are spent (at least one): a slow row takes fewer samples, never none. Returns
    ``timing``'s statistics (``repeats``: the samples taken) and ``out``, the first result."""
    t0 = time.perf_counter()
    out = block(call())
    first_ms = (time.perf_counter() - t0) * 1e3
    samples, start = [], time.perf_counter()
    for _ in range(max(1, repeats)):
        t = time.perf_counter()
        block(call())
        samples.append((time.perf_counter() - t) * 1e3)
        if budget_s is not None and time.perf_counter() - start >= budget_s:
            break
    median = statistics.median(samples)
    return {"median_ms": median, "min_ms": min(samples), "max_ms": max(samples),
            "repeats": len(samples), "compile_s": max(first_ms - median, 0.0) / 1e3, "out": out}


def _compile_scene(scene, camera, pipeline_specs, width, height, workers: int) -> list:
    """Each pipeline's compiled program (or the exception that stopped it), compiled side by
    side in ``workers`` threads (XLA compiles outside the GIL) and all finished before any
    is timed, so that no compile shares the machine with a timed call."""
    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.timing import compile_program

    def build(spec):
        """(the images-only program, timed; the instrumented one, for the counts)."""
        pname, pparams = parse_spec(spec, "pipeline")
        cfg = make_config(pname, width=width, height=height, **pparams)
        return tuple(compile_program(get_pipeline(pname), scene, camera, cfg, outputs=o)
                     for o in ("images", "all"))

    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        futures = [pool.submit(build, spec) for spec in pipeline_specs]
        wait(futures)
    return [f.exception() or f.result() for f in futures]


def time_pipelines(scene_specs, pipeline_specs, width: int, height: int, *, repeats: int = 5,
                   budget_s: float | None = None, compile_workers: int = 1):
    """Yield one row per (scene, pipeline), every one of them: a failure is a row with its
    reason in ``skipped``, a slow row takes fewer repeats (``budget_s`` per row, see
    ``time_row``). A scene's programs compile side by side (``compile_workers`` threads;
    ``compile_s`` is then the wall time of a compile that shared the machine with the rest),
    then each is timed alone."""
    from jaxrender.scene import default_camera
    from jaxrender.shading import load_lit_scene

    for scene_spec in scene_specs:
        base = dict(scene=scene_spec, resolution=f"{width}x{height}")
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
        programs = _compile_scene(scene, camera, pipeline_specs, width, height, compile_workers)
        for pipe_spec, comp in zip(pipeline_specs, programs):
            row = dict(base, pipeline=pipe_spec, compile_workers=compile_workers)
            try:
                if isinstance(comp, BaseException):
                    raise comp
                timed, instrumented = comp
                r = time_row(lambda c=timed, s=scene, k=camera: c.call(s, k), repeats, budget_s)
                r.pop("out")
                row.update(r, compile_s=timed.compile_ms / 1e3)
                counts = getattr(block(instrumented.call(scene, camera)), "counts", None) or {}
                for k in COUNT_COLUMNS:
                    if k in counts:
                        row[k] = float(counts[k])
            except Exception as e:  # noqa: BLE001
                row["skipped"] = f"{type(e).__name__}: {e}"[:200]
            yield row


COLUMNS = ["scene", "pipeline", "resolution", "median_ms", "min_ms", "repeats", "compile_s",
           "shade_invocations", "overshading", "skipped"]
