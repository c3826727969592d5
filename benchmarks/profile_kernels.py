"""Where a compiled program spends its time, kernel by kernel, from JAX's own profiler trace.

    python benchmarks/profile_kernels.py raster --resolution 1920x1080 --triangles 2600000
    python benchmarks/profile_kernels.py deferred --scene terrain --resolution 1920x1080
    python benchmarks/profile_kernels.py deferred --set chunk=65536

Traces a few steady-state calls (``jax.profiler.trace``), reads the XSpace back in-process
(``jax.profiler.ProfileData``, no TensorBoard needed) and prints, per call: the wall time, the
summed kernel time, the number of kernels launched and the kernels that took the most time. On a
GPU the events are the device's kernels; on a CPU, XLA's thunks on its worker threads.
"""

from __future__ import annotations

import argparse
import collections
import glob
import os
import tempfile
import time

import jax

from jaxrender.parsing import help_summary, parse_settings, parse_spec, resolution_arg
from jaxrender.timing import device_description

_HOST_NOISE = ("ThreadpoolListener", "end: ", "ThunkExecutor", "$", "PjitFunction")


def kernel_events(xplane_path: str) -> list[tuple[str, float, float]]:
    """(name, duration us, start us) of every kernel (GPU) or XLA thunk (CPU) in a trace."""
    from jax.profiler import ProfileData

    data = ProfileData.from_file(xplane_path)
    gpu = [p for p in data.planes if p.name.startswith("/device:GPU")]
    out = []
    if gpu:
        for plane in gpu:
            for line in plane.lines:
                # The "XLA Ops"/"XLA Modules" lines repeat the kernels at a coarser level.
                if "stream" not in line.name.lower():
                    continue
                out += [(e.name, e.duration_ns / 1e3, e.start_ns / 1e3) for e in line.events]
        return out
    for plane in data.planes:
        if plane.name != "/host:CPU":
            continue
        for line in plane.lines:
            if not line.name.startswith("tf_XLA"):
                continue
            out += [(e.name, e.duration_ns / 1e3, e.start_ns / 1e3) for e in line.events
                    if not e.name.startswith(_HOST_NOISE)]
    return out


def hlo_sources(text: str) -> dict[str, str]:
    """Instruction name (dots as underscores, as kernels are named) -> 'scope @ file:line' of
    the JAX operation it came from, read off the optimized HLO text's metadata."""
    import re

    pat = re.compile(r'^\s*(?:ROOT )?%?([\w.\-]+) = .*?metadata=\{op_name="([^"]*)"'
                     r'(?: source_file="([^"]*)")?(?: source_line=(\d+))?')
    out = {}
    for line in text.splitlines():
        m = pat.match(line)
        if m:
            name, op, src, ln = m.groups()
            where = f" @ {os.path.basename(src)}:{ln}" if src else ""
            # The whole scope path: the table shortens it, a scope's sum matches anywhere in it.
            out[name.replace(".", "_")] = f"{op.split('/', 1)[-1]}{where}"
    return out


def source_of(sources: dict[str, str], kernel: str, default: str = "") -> str:
    """The source ``hlo_sources`` found for a kernel (kernels name instructions with dots as
    underscores)."""
    return sources.get(kernel.replace(".", "_"), default)


def short_source(source: str, keep: int = 60) -> str:
    """A source for the table: the last ``keep`` characters of its scope path, and its place."""
    op, at, where = source.partition(" @ ")
    return f"{op[-keep:]}{at}{where}"


def profile_call(fn, *args, calls: int = 5, top: int = 15, label: str = "",
                 scopes: tuple[str, ...] = (), copies: bool = False, scope_top: int = 0,
                 hlo_text: str | None = None) -> dict:
    """Trace ``calls`` steady-state calls of ``fn(*args)`` and print the kernel table; with
    ``scopes``, also the kernel time whose source lies under each named scope, and that
    scope's ``scope_top`` longest kernels. ``fn`` is jitted here unless ``hlo_text`` (its
    compiled program's text) says it is compiled already."""
    if hlo_text is None:
        fn = jax.jit(fn)
    jax.block_until_ready(fn(*args))  # compile and warm up outside the trace
    jax.block_until_ready(fn(*args))
    t0 = time.perf_counter()
    for _ in range(calls):
        jax.block_until_ready(fn(*args))
    wall_ms = (time.perf_counter() - t0) / calls * 1e3
    with tempfile.TemporaryDirectory() as d:
        with jax.profiler.trace(d):
            for _ in range(calls):
                jax.block_until_ready(fn(*args))
        (path,) = glob.glob(os.path.join(d, "**", "*.xplane.pb"), recursive=True)
        events = kernel_events(path)
    total = collections.defaultdict(float)
    count = collections.Counter()
    span_ms = device_span_ms(events, calls)
    for name, us, _ in events:
        total[name] += us
        count[name] += 1
    kernel_ms = sum(total.values()) / calls / 1e3
    print(f"\n## {label}: wall {wall_ms:.3f} ms/call (untraced), kernels {kernel_ms:.3f} ms/call, "
          f"{len(events) / calls:.0f} launches/call, device span {span_ms:.3f} ms/call "
          f"(first kernel start to last kernel end; span - kernels = device idle)")
    try:
        sources = hlo_sources(hlo_text if hlo_text is not None
                              else fn.lower(*args).compile().as_text())
    except Exception as e:  # noqa: BLE001 - the table is still useful without sources
        sources = {}
        print(f"(no HLO sources: {type(e).__name__}: {e})")
    for scope in scopes:  # kernels fused across scopes count where XLA named them
        inside = {n: us for n, us in total.items()
                  if f"{scope}/" in source_of(sources, n)}
        print(f"scope {scope}: kernels {sum(inside.values()) / calls / 1e3:.3f} ms/call")
        for name, us in sorted(inside.items(), key=lambda kv: -kv[1])[:scope_top]:
            print(f"    {name[:48]}: {us / calls / 1e3:.3f} ms/call in {count[name] / calls:.0f} "
                  f"launches")
    if copies:
        print_copy_neighbours(events, sources, calls)
    print("| kernel | ms/call | launches/call | from |\n|---|---:|---:|---|")
    for name, us in sorted(total.items(), key=lambda kv: -kv[1])[:top]:
        print(f"| {name[:48]} | {us / calls / 1e3:.3f} | {count[name] / calls:.0f} | "
              f"{short_source(source_of(sources, name))} |")
    return {"label": label, "wall_ms": wall_ms, "kernel_ms": kernel_ms,
            "launches": len(events) / calls,
            "top": sorted(((n, t / calls / 1e3, count[n] / calls) for n, t in total.items()),
                          key=lambda r: -r[1])[:top]}


def print_copy_neighbours(events, sources: dict, calls: int) -> None:
    """Copies carry no HLO name (a conditional's or a loop's buffers, say): name each by the
    kernels launched just before and after it, so it can be traced to the code around it."""
    ev = sorted(events, key=lambda e: e[2])
    where = collections.defaultdict(float)
    for i, (name, us, _) in enumerate(ev):
        if "memcpy" not in name.lower():
            continue
        around = []
        for j in (i - 1, i + 1):
            if 0 <= j < len(ev) and "memcpy" not in ev[j][0].lower():
                around.append(source_of(sources, ev[j][0], ev[j][0])[-50:])
        where[(name[:16], " / ".join(around))] += us
    print("| copy | ms/call | kernels before / after |\n|---|---:|---|")
    for (name, around), us in sorted(where.items(), key=lambda kv: -kv[1])[:12]:
        print(f"| {name} | {us / calls / 1e3:.3f} | {around} |")


def device_span_ms(events, calls: int) -> float:
    """Median over calls of (last kernel end - first kernel start): the calls are told apart
    by the calls - 1 largest gaps between kernels (each call waits for the previous one)."""
    import numpy as np

    if not events:
        return float("nan")
    ev = sorted((start, start + dur) for _, dur, start in events)
    starts = np.array([a for a, _ in ev])
    ends = np.maximum.accumulate(np.array([b for _, b in ev]))
    gaps = starts[1:] - ends[:-1]
    cuts = np.sort(np.argsort(gaps)[::-1][: calls - 1]) + 1 if calls > 1 else np.array([], int)
    bounds = [0, *cuts.tolist(), len(ev)]
    spans = [ends[b - 1] - starts[a] for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
    return float(np.median(spans)) / 1e3


def pipeline_case(what: str, scene_spec: str, width: int, height: int, settings: list[str],
                  shader_cost: int | None):
    """(scene, its default camera, pipeline, config, label) of a command line's pipeline
    ``what`` on ``scene_spec`` (``--scene``), ``settings`` its ``--set KEY=VALUE`` overrides
    and ``shader_cost`` the scene's (None: its own)."""
    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.scene import default_camera
    from jaxrender.shading import load_lit_scene

    name, params = parse_spec(scene_spec, "--scene")
    if shader_cost is not None:
        params["effects"] = {**params.get("effects", {}), "shader_cost": shader_cost}
    scene = load_lit_scene(name, **params)
    cfg = make_config(what, width=width, height=height, **parse_settings(settings, "--set"))
    cost = "" if shader_cost is None else f" shader_cost={shader_cost}"
    label = f"{what} {scene_spec}{cost} {width}x{height} {' '.join(settings)}"
    return scene, default_camera(scene), get_pipeline(what), cfg, label


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("what", help="'raster' or a pipeline name (forward, deferred, ...)")
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--triangles", type=int, default=164_000, help="terrain size for 'raster'")
    ap.add_argument("--scene", default="terrain",
                    help="scene for a pipeline, 'name' or 'name:key=value,...'")
    ap.add_argument("--shader-cost", type=int, default=None, metavar="N",
                    help="the scene's shader cost (Effects.shader_cost: 1 + N light layers a "
                         "point); default: the scene's own")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="pipeline config override, e.g. chunk=65536")
    ap.add_argument("--traversal", default="auto", help="for 'raster': auto, bbox, recompute, spans")
    ap.add_argument("--calls", type=int, default=5)
    ap.add_argument("--top", type=int, default=15)
    ap.add_argument("--frames", type=int, default=0,
                    help="profile a still camera's sequence of this many frames (state carried: "
                         "TAA's resolve runs); 0: one frame")
    ap.add_argument("--copies", action="store_true",
                    help="also name the device copies by the kernels around them")
    ap.add_argument("--scope", action="append", default=[],
                    help="sum the kernel time under this named scope (e.g. taa)")
    ap.add_argument("--scope-top", type=int, default=0, metavar="N",
                    help="also list each scope's N longest kernels")
    args = ap.parse_args(argv)
    w, h = args.resolution
    print(f"device: {device_description()}, jax {jax.__version__}")
    if args.what == "raster":
        from jaxrender.bench.raster import static_args, terrain_clip
        from jaxrender.raster.rasterize import rasterize_traced

        clip, faces = terrain_clip(args.triangles, w, h)
        fn = jax.jit(lambda c, f: rasterize_traced(c, f, **static_args(faces.shape[0], w, h),
                                             traversal=args.traversal))
        profile_call(fn, clip, faces, calls=args.calls, top=args.top,
                     label=f"raster {w}x{h} {faces.shape[0]} triangles ({args.traversal})")
        return 0
    sc, cam, pipe, cfg, label = pipeline_case(args.what, args.scene, w, h, args.set,
                                              args.shader_cost)
    scopes = tuple(args.scope)
    cameras = cam
    if args.frames:
        from jaxrender.scene.camera_path import stack

        cameras, label = stack([cam] * args.frames), f"{label} sequence of {args.frames} frames"
    # The program as the benchmarks compile it (its own compiler options, host-side
    # preparation outside), returning the images alone as a timed run does.
    run, text = pipeline_program(pipe, sc, cameras, cfg, sequence=bool(args.frames))
    profile_call(run, calls=args.calls, top=args.top, label=label, scopes=scopes,
                 scope_top=args.scope_top, copies=args.copies, hlo_text=text)
    return 0


def pipeline_program(pipe, scene, cameras, cfg, sequence: bool):
    """(``run() -> image``, its compiled program's text): the program of ``pipe`` compiled as
    ``program.compile`` does, images only."""
    from jaxrender.pipelines import program

    lowered, prepared = program.lower(pipe, scene, cameras, cfg, sequence=sequence,
                                      outputs="images")
    compiled = lowered.compile()
    call = program.bind(pipe, cfg, compiled, prepared)
    return (lambda: call(scene, cameras).image), compiled.as_text()

if __name__ == "__main__":
    raise SystemExit(main())
