"""The ``jaxrender`` command. ``jaxrender COMMAND --help`` describes each command.

A user's mistake (a bad study file, an unknown scene or pipeline, a missing run directory)
prints one line to stderr and exits with status 2, without a traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tomllib
from pathlib import Path

from jaxrender import catalog
from jaxrender.bench import add_arguments as bench_arguments  # argparse only: no jax yet
from jaxrender.errors import StudyError, UserError
from jaxrender.parsing import parse_settings, positive_int_arg, resolution_arg


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, status 2
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


# ------------------------------------------------------------------ commands


def cmd_study(a) -> int:
    from jaxrender.figures import draw_run_figures
    from jaxrender.seeds.report import tables_for_study
    from jaxrender.study import load_study, run_study

    study = load_study(a.file, configs=a.configs).with_overrides(frames=a.frames,
                                                                 resolution=a.resolution)
    given = [f for f in ("coordinator", "num_processes", "process_id")
             if getattr(a, f) is not None]
    if given and not a.distributed:
        raise UserError(f"--{given[0].replace('_', '-')} needs --distributed")
    if a.distributed:
        from jaxrender.study.devices import initialize_distributed

        initialize_distributed(a.coordinator, a.num_processes, a.process_id)
    out = Path(a.out) if a.out else Path("runs") / study.name
    print(f"study {study.name}: {len(study.scenes)} scene(s), {len(study.paths)} camera "
          f"path(s), {len(study.variants)} pipeline variant(s) at {study.resolution[0]}x"
          f"{study.resolution[1]} -> {out}")
    result = run_study(study, out, force=a.force, progress=not a.no_progress,
                       devices=a.devices)
    import jax

    if jax.process_index() != 0:  # a distributed run's other processes: the first exports
        return 0
    tables_for_study(study.name, result.rows, out)  # a source's table, if it measures one
    if not a.no_figures:
        draw_run_figures(result)
    print(f"results: {out / 'results.csv'}")
    return 0


def cmd_report(a) -> int:
    from jaxrender.seeds import report

    out = a.out or a.runs
    claims = report.collect(a.runs, read_only=a.read, resolution=a.resolution,
                            frames=a.frames, force=a.force, progress=not a.no_progress,
                            tables_to=out)
    md, csv_path = report.write_report(claims, out)
    print(report.format_markdown(claims))
    print(f"report: {md}, {csv_path}")
    return 0


def cmd_validate(a) -> int:
    from jaxrender.study.schema import load_study

    s = load_study(a.file, configs=a.configs)
    per_variant = sum(p.frames for p in s.paths) * len(s.scenes)
    frames = per_variant * len(s.variants)
    warm = s.warmup_frames * len(s.paths) * len(s.scenes) * len(s.variants)
    extra = f", plus {warm} warm-up frames" if warm else ""
    matches = sum(len(p.match) for p in s.pipelines) * len(s.paths) * len(s.scenes)
    extra += f", and {matches} matched point(s) to bisect" if matches else ""
    print(f"{a.file}: ok ({len(s.scenes)} scene(s), {len(s.paths)} path(s), "
          f"{len(s.variants)} variant(s), {frames} frames to render{extra})")
    return 0


def cmd_figures(a) -> int:
    from jaxrender.figures.make import render_figures
    from jaxrender.study.specs import FIGURES

    run = Path(a.run_dir)
    if not (run / "results.csv").exists():
        raise UserError(f"{run}: not a study output directory (no results.csv)")
    for n in a.only or ():
        if n not in FIGURES:
            raise UserError(f"--only: unknown figure {n!r}; known: {', '.join(FIGURES)}")
    render_figures(run, tuple(a.only) if a.only else FIGURES, out_dir=a.to)
    return 0


def cmd_scenes(a) -> int:
    from jaxrender.study import backend

    rows = backend.builtin_scenes()
    width = max((len(n) for n, _ in rows), default=0)
    for name, desc in rows:
        print(f"{name.ljust(width)}  {desc}")
    for entry in catalog.entries("scenes", catalog.local_configs(Path.cwd())).values():
        print(f"{entry.name.ljust(width)}  (scene file, {entry.describe()})")
    return 0


def cmd_studies(a) -> int:
    entries = catalog.entries("studies").values()
    width = max((len(e.name) for e in entries), default=0)
    for e in entries:
        description = tomllib.loads(e.path.read_text()).get("description", "")
        print(f"{e.name.ljust(width)}  {description}")
    print("\nrun one with `jaxrender study NAME` (writes runs/NAME under this folder)")
    return 0


def cmd_presets(a) -> int:
    try:
        local = catalog.local_configs(Path.cwd(), a.configs)
    except FileNotFoundError as e:
        raise UserError(f"--configs: {e}") from None
    for kind in ("paths", "pipelines", "scenes"):
        entries = catalog.entries(kind, local).values()
        print(f"{catalog.KINDS[kind]}s ({kind}):")
        width = max((len(e.name) for e in entries), default=0)
        for e in entries:
            print(f"  {e.name.ljust(width)}  {e.describe()}")
        if not entries:
            print("  (none)")
    return 0


def cmd_pipelines(a) -> int:
    from jaxrender.pipelines.registry import list_pipelines

    pipes = list_pipelines()
    if not pipes:
        print("(no pipelines registered yet)")
    width = max((len(p.name) for p in pipes), default=0)
    for p in pipes:
        print(f"{p.name.ljust(width)}  {p.description}")
    return 0


def cmd_render(a) -> int:
    import matplotlib.image

    from jaxrender.figures.data import display_image
    from jaxrender import timing
    from jaxrender.study import backend
    from jaxrender.study.store import json_number
    from jaxrender.study.schema import check_params
    from jaxrender.study.tables import Checker

    w, h = a.resolution or (320, 180)
    params = check_params(Checker("--set"), "", a.pipeline, parse_settings(a.set, "--set"), (w, h))
    scene = backend.load_scene(a.scene, {})
    camera = backend.default_camera(scene)
    pipe = backend.pipeline(a.pipeline)
    cfg = backend.make_config(a.pipeline, w, h, params)
    comp = timing.compile_program(pipe, scene, camera, cfg)
    frame, ms, _ = timing.time_call(comp.call, scene, camera, repeats=a.repeats, warmup=1)
    import numpy as np

    img = np.asarray(frame.image, np.float32)
    out = Path(a.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    matplotlib.image.imsave(out, display_image(img))
    counts = {k: json_number(v) for k, v in (frame.counts or {}).items()}
    counts = {k: v for k, v in counts.items() if v is not None}
    if a.json:
        print(json.dumps({"image": str(out), "scene": a.scene, "pipeline": a.pipeline,
                          "params": params, "width": w, "height": h, "time_ms": ms,
                          "timed_outputs": "all", "compile_ms": comp.compile_ms,
                          "counts": counts}, sort_keys=True))
    else:
        print(f"wrote {out} ({w}x{h}, {a.pipeline}, {ms:.2f} ms with the counts)")
        for k in sorted(counts):
            print(f"  {k}: {counts[k]}")
    return 0


def cmd_reference(a) -> int:
    from jaxrender.study import cache, references

    if a.action == "clear":
        n = cache.clear()
        print(f"removed {n} cached reference frame(s) from {cache.cache_dir()}")
    elif a.action == "info":
        print(json.dumps(cache.info(), indent=2))
    else:
        from jaxrender.study.schema import load_study

        study = load_study(a.study, configs=a.configs).with_overrides(
            frames=a.frames, resolution=a.resolution)
        n = references.rebuild(study)
        print(f"rebuilt {n} reference frame(s) in {cache.cache_dir()}")
    return 0


def cmd_bench(a) -> int:
    from jaxrender.bench import run

    return run(a)


# ------------------------------------------------------------------ the parser


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="jaxrender", description="Study real-time shading architectures in JAX.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in (_add_study, _add_inspection, _add_render, _add_bench, _add_reference):
        add(sub)
    return p


def _add_study(sub) -> None:
    s = sub.add_parser("study", help="run a study file", description=(
        "Render every (scene, camera path, pipeline variant, frame) of a study, score it "
        "against the cached reference, time it, and write results.jsonl, results.csv, the "
        "resolved config and the figures. Rerunning resumes; --force recomputes. A pipeline "
        "entry's shader_cost (in params or sweep) sets the scene's shader cost for its "
        "variants, in extra light layers: each shaded point evaluates every light 1 + "
        "shader_cost times; rows carry shader_cost and shading_work = shade_invocations x "
        "(1 + shader_cost), and a shader_cost sweep writes time_fits.csv (fixed cost, ms per "
        "million layer evaluations, crossover against deferred)."))
    s.add_argument("file", help="a study TOML file (e.g. studies/quickstart.toml) or a bundled "
                   "study's name (e.g. quickstart; `jaxrender studies` lists them)")
    _configs_argument(s)
    s.add_argument("--out", help="output directory (default runs/NAME)")
    s.add_argument("--frames", type=positive_int_arg, help="frames per camera path (overrides)")
    s.add_argument("--resolution", type=resolution_arg, help="WxH (overrides)")
    s.add_argument("--force", action="store_true", help="discard stored rows and recompute")
    s.add_argument("--no-figures", action="store_true", help="do not draw figures")
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.add_argument("--devices", type=positive_int_arg, help=(
        "spread the sequences over this many local devices (default: all; each scene and "
        "variant runs on one, and a device's sequences are timed while the others run)"))
    s.add_argument("--distributed", action="store_true", help=(
        "one process per host: jax.distributed.initialize() from the cluster's environment "
        "(or --coordinator, --num-processes, --process-id); the processes share --out and "
        "split the study, the first exports the merged results"))
    s.add_argument("--coordinator", help="with --distributed: the coordinator's host:port")
    s.add_argument("--num-processes", type=positive_int_arg, help="with --distributed")
    s.add_argument("--process-id", type=int, help="with --distributed: this process's index")
    s.set_defaults(fn=cmd_study)

    s = sub.add_parser("report", help="every source's published numbers beside ours",
                       description=(
        "Run the study of every source jaxrender reproduces (DACS: dacs_vs_checkerboard) into "
        "RUNS/<study> (resuming what is stored there), or with --read read those runs, and "
        "print and write report.md and report.csv: source, figure or slide, quantity, the "
        "published value, ours, our conditions and the verdict (reproduced within the stated "
        "tolerance, direction reproduced, not reproduced, not measured) with the reason. "
        "--resolution and --frames run it small (on a CPU); the published numbers were "
        "measured at full size."))
    s.add_argument("--runs", type=Path, default=Path("runs") / "seeds",
                   help="folder of the sources' study runs (default runs/seeds)")
    s.add_argument("--out", type=Path, help="where report.md, report.csv and each source's own "
                   "table (dacs_table.md) go (default RUNS)")
    s.add_argument("--read", action="store_true",
                   help="read the runs in RUNS, render nothing")
    s.add_argument("--frames", type=positive_int_arg, help="frames per camera path (overrides)")
    s.add_argument("--resolution", type=resolution_arg, help="WxH (overrides)")
    s.add_argument("--force", action="store_true", help="discard stored rows and recompute")
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(fn=cmd_report)


def _configs_argument(s) -> None:
    s.add_argument("--configs", type=Path, metavar="DIR", help=(
        "a configs folder (holding paths/, pipelines/, scenes/) whose presets add to and "
        "override the built-ins (default: the nearest configs/ at or above the study file)"))


def _add_inspection(sub) -> None:
    """validate, figures, scenes, pipelines: commands that render nothing."""
    s = sub.add_parser("validate", help="check a study file without running it",
                       description="Validate a study file and print what it would render.")
    s.add_argument("file", help="a study TOML file or a bundled study's name")
    _configs_argument(s)
    s.set_defaults(fn=cmd_validate)

    s = sub.add_parser("studies", help="list the bundled studies",
                       description="List the studies that ship with jaxrender, one line each.")
    s.set_defaults(fn=cmd_studies)

    s = sub.add_parser("presets", help="list the presets and where each comes from",
                       description=("List the camera path presets, pipeline presets and scene "
                                    "files: the built-in ones and those of a local configs/ "
                                    "folder (the nearest at or above this folder, or "
                                    "--configs), which override built-ins of the same name."))
    _configs_argument(s)
    s.set_defaults(fn=cmd_presets)

    s = sub.add_parser("figures", help="redraw the figures of a run directory",
                       description="Redraw the figures from stored results, without rendering.")
    s.add_argument("run_dir", help="a study output directory (holding results.csv)")
    s.add_argument("--only", nargs="+", metavar="NAME", help="draw only these figures")
    s.add_argument("--to", metavar="DIR", help="write the figures here (default RUN_DIR/figures)")
    s.set_defaults(fn=cmd_figures)

    s = sub.add_parser("scenes", help="list the built-in scenes",
                       description="List the built-in scenes and the scene files (built-in, "
                       "and those of the nearest local configs/scenes).")
    s.set_defaults(fn=cmd_scenes)

    s = sub.add_parser("pipelines", help="list the registered pipelines",
                       description="List the registered pipelines, one line each.")
    s.set_defaults(fn=cmd_pipelines)


def _add_render(sub) -> None:
    s = sub.add_parser("render", help="render one frame to a PNG", description=(
        "Render one frame of SCENE from its default camera with one pipeline, write the image "
        "and print the counts. The time is the single-frame program's with its counts and "
        "views (a study times the images alone, see [timing] outputs)."))
    s.add_argument("scene", help="a built-in scene name or a scene TOML file")
    s.add_argument("--pipeline", required=True, help="a registered pipeline type")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="a pipeline parameter (value in TOML syntax); repeatable")
    s.add_argument("--resolution", type=resolution_arg, help="WxH (default 320x180)")
    s.add_argument("--repeats", type=positive_int_arg, default=3, help="timed repeats (median)")
    s.add_argument("-o", "--output", required=True, help="the PNG to write")
    s.add_argument("--json", action="store_true", help="print the counts as JSON")
    s.set_defaults(fn=cmd_render)


def _add_bench(sub) -> None:
    s = sub.add_parser("bench", help="time the rasterizer, pipelines and metrics", description=(
        "Rasterizer throughput against triangle count and resolution, each pipeline's frame "
        "time on each built-in scene, metric times, compile times apart and peak device "
        "memory: markdown tables on stdout, every row in --json."))
    bench_arguments(s)
    s.set_defaults(fn=cmd_bench)


def _add_reference(sub) -> None:
    s = sub.add_parser("reference", help="manage the reference cache", description=(
        "The reference cache: $JAXRENDER_CACHE/reference, else "
        "$XDG_CACHE_HOME/jaxrender/reference (~/.cache/jaxrender/reference)."))
    rsub = s.add_subparsers(dest="action", required=True, parser_class=_Parser)
    r = rsub.add_parser("rebuild", help="re-render the reference frames of a study",
                        description="Delete and re-render the reference frames a study uses.")
    r.add_argument("study", help="a study TOML file or a bundled study's name")
    _configs_argument(r)
    r.add_argument("--frames", type=positive_int_arg)
    r.add_argument("--resolution", type=resolution_arg)
    r.set_defaults(fn=cmd_reference)
    r = rsub.add_parser("clear", help="delete every cached reference",
                        description="Delete every cached reference frame.")
    r.set_defaults(fn=cmd_reference)
    r = rsub.add_parser("info", help="where the cache is and how big",
                        description="Print the cache location, entry count and code version.")
    r.set_defaults(fn=cmd_reference)


def main(argv=None) -> int:
    # A study compiles many programs at once, and on a GPU each compile autotunes in device
    # memory; with JAX's default preallocation (75% of it held from the first array) the
    # bundled time_follows_work study ran out of memory while compiling on an H200. Read when
    # the backend starts, so this holds unless the user set it.
    os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")
    args = build_parser().parse_args(argv)
    try:
        return args.fn(args)
    except (UserError, StudyError) as e:
        print(f"jaxrender: error: {e}", file=sys.stderr)
        return 2
    except OverflowError as e:  # pipelines.PipelineOverflow: names the pipeline and the fix
        print(f"jaxrender: error: {e}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("jaxrender: interrupted; rerun the same command to resume", file=sys.stderr)
        return 130
