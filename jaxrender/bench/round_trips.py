"""Host round trips per frame: how many times a program's control flow reads a value back from
the device, counted by running its jaxpr one primitive at a time.

On a GPU, XLA runs a ``while`` loop by copying its condition to the host before every
iteration (and once more to stop), and a ``cond``/``switch`` by copying its branch index
before launching the branch. Each copy drains the device's queue, and the next kernels are
launched only after it: on an H200 each cost about 50 µs of idle device at 1920x1080
(benchmarks/RESULTS.md, the fifteenth session), as much as a full-screen shading kernel. The
count of them follows from the data (a loop's trip count is its work list's chunks), so it
is read here from an actual run, not from the program's text:

- every evaluation of a ``while`` loop's condition is one read;
- every ``cond`` is one read, except one chosen by platform (``lax.platform_dependent``),
  which the compiler resolves; its GPU branch is the one followed;
- a ``scan`` has a static trip count and reads nothing itself; its body runs as often.

Counts are an upper bound of what XLA does: it may turn a small ``cond`` into a select.
Only the count is measured, never time, so it runs on a CPU at the resolution it reports::

    python -m jaxrender.bench.round_trips --scenes room glass --pipelines deferred forward
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import time

import jax
from jax.extend.core import ClosedJaxpr, Literal
import numpy as np

# Primitives that call one jaxpr with their own operands: followed inside, so the loops they
# hold are counted. Any other primitive is bound whole; one that holds a loop or a branch in
# a jaxpr of its own is refused (``held_reads``), so that no read goes uncounted.
CALLS = {"pjit": "jaxpr", "jit": "jaxpr", "closed_call": "call_jaxpr",
         "custom_jvp_call": "call_jaxpr", "custom_vjp_call": "call_jaxpr",
         "custom_vjp_call_jaxpr": "fun_jaxpr", "remat": "jaxpr", "checkpoint": "jaxpr"}
GPU_PLATFORMS = ("cuda", "gpu", "rocm")


@dataclasses.dataclass
class Tally:
    """Reads counted while a program runs: per frame (the outermost scan's iteration, None
    before it) and per place (the kind of read and the code that made it)."""

    frame: int | None = None
    frames_length: int | None = None  # the outermost scan's length, once it is entered
    reads: collections.Counter = dataclasses.field(default_factory=collections.Counter)

    def add(self, kind: str, where: str) -> None:
        self.reads[self.frame, kind, where] += 1

    def per_frame(self) -> dict:
        out = collections.Counter()
        for (frame, _, _), n in self.reads.items():
            out[frame] += n
        return dict(out)

    def places(self, frame) -> list[tuple[str, str, int]]:
        """(kind, where, reads) of one frame, most reads first."""
        rows = [(k, w, n) for (f, k, w), n in self.reads.items() if f == frame]
        return sorted(rows, key=lambda r: -r[2])


def where_of(eqn) -> str:
    """The named scope and the innermost jaxrender source line that made an equation."""
    scope = str(eqn.source_info.name_stack)
    line = ""
    tb = eqn.source_info.traceback
    for fr in (tb.frames if tb is not None else []):
        if "/jaxrender/" in fr.file_name and "/bench/" not in fr.file_name:
            line = f"{fr.file_name.rsplit('/jaxrender/', 1)[1]}:{fr.line_num}"
            break
    return f"{scope} {line}".strip()


def gpu_branch(platforms) -> int:
    """The branch a GPU compile takes of a ``cond`` chosen by platform."""
    for i, names in enumerate(platforms):
        if names is not None and any(p in GPU_PLATFORMS for p in names):
            return i
    return next(i for i, names in enumerate(platforms) if names is None)


def run_jaxpr(closed, args, tally: Tally, scans: int = 0):
    """Evaluate a ClosedJaxpr on concrete ``args``, counting reads into ``tally``; each value
    is dropped after its last use (a 1080p frame holds many capacity-sized lists)."""
    jaxpr = closed.jaxpr
    env = {}
    last_use = {}
    for i, eqn in enumerate(jaxpr.eqns):
        for v in eqn.invars:
            if not isinstance(v, Literal):
                last_use[v] = i

    def read(v):
        return v.val if isinstance(v, Literal) else env[v]

    env.update(zip(jaxpr.constvars, closed.consts))
    env.update(zip(jaxpr.invars, args))
    keep = {v for v in jaxpr.outvars if not isinstance(v, Literal)}
    for i, eqn in enumerate(jaxpr.eqns):
        ins = [read(v) for v in eqn.invars]
        with eqn.ctx.manager:
            outs = run_eqn(eqn, ins, tally, scans)
        if not eqn.primitive.multiple_results:
            outs = [outs]
        env.update(zip(eqn.outvars, outs))
        for v in eqn.invars:
            if not isinstance(v, Literal) and last_use.get(v) == i and v not in keep:
                env.pop(v, None)
    return [read(v) for v in jaxpr.outvars]


def run_eqn(eqn, ins, tally: Tally, scans: int):
    name, p = eqn.primitive.name, eqn.params
    if name == "while":
        return run_while(eqn, ins, tally, scans)
    if name == "cond":
        return run_cond(eqn, ins, tally, scans)
    if name == "scan":
        return run_scan(eqn, ins, tally, scans)
    if name == "platform_index":
        return np.int32(gpu_branch(p["platforms"]))
    if name in CALLS and CALLS[name] in p:
        return run_jaxpr(as_closed(p[CALLS[name]]), ins, tally, scans)
    if held_reads(p):
        raise NotImplementedError(f"{name} holds a loop or a branch that round_trips cannot "
                                  f"follow ({where_of(eqn)})")
    return eqn.primitive.bind(*ins, **eqn.primitive.get_bind_params(p))


def sub_jaxprs(params: dict):
    """The jaxprs among a primitive's parameters (a scatter's update function, say)."""
    for v in params.values():
        for x in (v if isinstance(v, (tuple, list)) else (v,)):
            if hasattr(x, "eqns"):
                yield x
            elif hasattr(x, "jaxpr") and hasattr(x.jaxpr, "eqns"):
                yield x.jaxpr


def held_reads(params: dict) -> bool:
    """Whether any jaxpr among ``params`` holds a ``while`` or a ``cond``."""
    return any(e.primitive.name in ("while", "cond") or held_reads(e.params)
               for j in sub_jaxprs(params) for e in j.eqns)


def as_closed(jaxpr):
    if hasattr(jaxpr, "consts"):
        return jaxpr
    return ClosedJaxpr(jaxpr, ())


def run_while(eqn, ins, tally: Tally, scans: int):
    p = eqn.params
    cc, bc = p["cond_nconsts"], p["body_nconsts"]
    cond_consts, body_consts, carry = ins[:cc], ins[cc:cc + bc], list(ins[cc + bc:])
    where = where_of(eqn)
    while True:
        tally.add("while", where)
        (go,) = run_jaxpr(p["cond_jaxpr"], cond_consts + carry, tally, scans)
        if not bool(np.asarray(go)):
            return carry
        carry = run_jaxpr(p["body_jaxpr"], body_consts + carry, tally, scans)


def run_cond(eqn, ins, tally: Tally, scans: int):
    p = eqn.params
    index, operands = ins[0], ins[1:]
    branches = p["branches"]
    if p.get("branches_platforms") is not None:  # resolved when compiled: no read
        i = gpu_branch(p["branches_platforms"])
    else:
        tally.add("cond", where_of(eqn))
        i = int(np.clip(np.asarray(index), 0, len(branches) - 1))
    return run_jaxpr(branches[i], operands, tally, scans)


def run_scan(eqn, ins, tally: Tally, scans: int):
    p = eqn.params
    nc, ncarry, length = p["num_consts"], p["num_carry"], p["length"]
    consts, carry, xs = ins[:nc], list(ins[nc:nc + ncarry]), ins[nc + ncarry:]
    outermost = scans == 0 and tally.frames_length is None
    if outermost:
        tally.frames_length = length
    ys = []
    steps = range(length - 1, -1, -1) if p["reverse"] else range(length)
    for i in steps:
        if outermost:
            tally.frame = i
        out = run_jaxpr(p["jaxpr"], consts + carry + [x[i] for x in xs], tally, scans + 1)
        carry, y = out[:ncarry], out[ncarry:]
        ys.append(y)
    if outermost:
        tally.frame = None
    if p["reverse"]:
        ys.reverse()
    n_y = len(eqn.outvars) - ncarry
    stacked = [jax.numpy.stack([y[j] for y in ys]) if ys else
               jax.numpy.zeros(eqn.outvars[ncarry + j].aval.shape,
                               eqn.outvars[ncarry + j].aval.dtype)
               for j in range(n_y)]
    return carry + stacked


def count(fn, *args) -> Tally:
    """Run ``fn(*args)`` primitive by primitive and return its reads. Traced as the program
    is; run with x64 on, so the int64 keys that parts of it trace under ``enable_x64`` keep
    their width when bound one at a time."""
    tally = Tally()
    closed = jax.make_jaxpr(fn)(*args)
    with jax.enable_x64(True):
        run_jaxpr(closed, jax.tree_util.tree_leaves(args), tally)
    return tally


def count_sequence(pipeline: str, scene_spec: str, width: int, height: int, frames: int = 2,
                   **params) -> Tally:
    """The reads of ``pipeline`` on ``scene_spec`` inside a ``frames``-frame pan, as the
    benchmarks time it (``render_sequence``'s program)."""
    from jaxrender.parsing import parse_spec
    from jaxrender.pipelines import get_pipeline, make_config, program
    from jaxrender.scene.camera_path import pan
    from jaxrender.shading import load_lit_scene

    name, scene_params = parse_spec(scene_spec, "--scenes")
    scene = load_lit_scene(name, **scene_params)
    cams = pan(scene.camera, frames, 1.0, height).cameras
    pipe = get_pipeline(pipeline)
    cfg = make_config(pipeline, width=width, height=height, **params)
    fixed, args, _ = program.arguments(pipe, scene, cams, cfg, sequence=True)
    return count(program.unjitted(fixed), *args)


def main(argv=None) -> int:
    import json
    from pathlib import Path

    from jaxrender.bench.report import print_table
    from jaxrender.parsing import help_summary, parse_spec, resolution_arg

    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["room", "foliage", "thin", "glass"])
    ap.add_argument("--pipelines", nargs="+", default=None,
                    help="names or 'name:key=value,...'; default: every registered pipeline "
                         "but the reference")
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--frames", type=int, default=2, help="frames of the pan (at least 1)")
    ap.add_argument("--places", type=int, default=0,
                    help="also list each row's N places with the most reads")
    ap.add_argument("--json", default=None, help="write the rows here")
    a = ap.parse_args(argv)
    if a.frames < 1:
        ap.error("--frames must be at least 1")
    from jaxrender.pipelines import list_pipelines

    specs = a.pipelines or [p.name for p in list_pipelines() if p.name != "reference"]
    w, h = a.resolution
    rows = []
    for scene in a.scenes:
        for spec in specs:
            name, params = parse_spec(spec, "--pipelines")
            t0 = time.perf_counter()
            try:
                tally = count_sequence(name, scene, w, h, a.frames, **params)
            except ValueError as e:  # a pipeline that refuses the scene: a row saying why
                rows.append({"scene": scene, "pipeline": spec, "error": str(e)[:160]})
                print(json.dumps(rows[-1]), flush=True)
                continue
            per = tally.per_frame()
            steady = [per.get(f, 0) for f in range(a.frames)]
            row = {"scene": scene, "pipeline": spec, "reads_per_frame": float(np.mean(steady)),
                   "reads_by_frame": steady, "reads_outside_frames": per.get(None, 0),
                   "seconds": round(time.perf_counter() - t0, 1)}
            row["places"] = [{"kind": k, "where": wh, "reads_per_frame": n / a.frames}
                             for k, wh, n in _merged_places(tally, a.frames)]
            rows.append(row)
            print(json.dumps({k: v for k, v in row.items() if k != "places"}), flush=True)
            for place in row["places"][:a.places]:
                print(f"    {place['reads_per_frame']:7.1f} {place['kind']:5} {place['where']}")
    print(f"\n{w}x{h}, {a.frames}-frame pan at 1 px/frame, reads a frame (mean over frames), "
          f"jax {jax.__version__}, {time.strftime('%Y-%m-%d')}\n")
    print_table(rows, ["scene", "pipeline", "reads_per_frame", "reads_outside_frames", "error"])
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))
    return 0


def _merged_places(tally: Tally, frames: int) -> list[tuple[str, str, int]]:
    """(kind, where, reads over all frames), most first."""
    merged = collections.Counter()
    for f in range(frames):
        for k, wh, n in tally.places(f):
            merged[k, wh] += n
    return [(k, wh, n) for (k, wh), n in merged.most_common()]


if __name__ == "__main__":
    raise SystemExit(main())
