"""A pipeline's GPU program compiled on a machine without a GPU: its kernel launches, counted.

    pip install "jax-cuda12-plugin==$(python -c 'import jax; print(jax.__version__)')" \
        "jax-cuda12-pjrt==$(python -c 'import jax; print(jax.__version__)')"
    JAX_SKIP_CUDA_CONSTRAINTS_CHECK=1 python benchmarks/offline_kernels.py dacs --scene foliage
    PYTHONPATH=.v/TREE JAX_SKIP_CUDA_CONSTRAINTS_CHECK=1 python -P benchmarks/offline_kernels.py ...

XLA's GPU compiler runs here for the card that ``--target`` describes (a GpuTargetConfigProto;
``benchmarks/targets/h100_sxm.txtpb`` by default), through a compile-only device, so the
fusion decisions are those of this jaxlib's XLA for that card. Nothing runs, so nothing is
timed: the count says how many kernels each part of the program launches, which on a GPU
costs a few microseconds apiece and, for each loop iteration and branch, a read back to the
host. The lent machines are scarce; a launch count read here tells which variant is worth
timing there.

Each control computation (the entry, a while loop's body and condition, a conditional's
branch) is listed with the instructions in it that launch a kernel or copy: fusions, custom
calls (sorts, for instance), copies and any unfused operation. A program runs the entry once,
a loop body per iteration and one branch of a conditional per execution, so the counts are
per execution of each, not per frame.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import sys
from pathlib import Path

import jax

# This checkout's package, unless PYTHONPATH names a tree of its own (a variant's, .v/TREE).
if not any((Path(p) / "jaxrender").is_dir()
           for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

sys.path.insert(0, str(Path(__file__).resolve().parent))  # its sibling, profile_kernels
from jaxrender.parsing import help_summary, resolution_arg  # noqa: E402
from profile_kernels import pipeline_case  # noqa: E402

TARGETS = Path(__file__).resolve().parent / "targets"
# Instructions that launch nothing: values, tuples, views and the control flow itself.
NOT_LAUNCHED = frozenset({
    "parameter", "constant", "tuple", "get-tuple-element", "bitcast", "while", "conditional",
    "call", "after-all", "opt-barrier", "partition-id", "replica-id", "add-dependency",
})
_HEAD = re.compile(r"(ENTRY )?%(\S+) ")
_OPCODE = re.compile(r"^\s*(?:ROOT )?%\S+ = .*? ([a-z][a-z0-9\-]*)\(")


def computations(hlo_text: str) -> tuple[dict[str, str], str]:
    """({computation name: its text}, the entry's name) of an HLO module's text."""
    blocks, entry = {}, None
    for block in re.split(r"\n(?=(?:ENTRY )?%)", hlo_text):
        m = _HEAD.match(block.split("\n", 1)[0])
        if m:
            blocks[m.group(2)] = block
            entry = m.group(2) if m.group(1) else entry
    if entry is None:
        raise ValueError("no ENTRY computation in the HLO text")
    return blocks, entry


def control_computations(hlo_text: str) -> dict[str, str]:
    """{name: role} of the computations the program runs as such (role "entry", "while-body",
    "while-condition", "branch" or "call"), found from the entry through the calls."""
    blocks, entry = computations(hlo_text)
    refs = (("while-condition", r"condition=%([\w.\-]+)"), ("while-body", r"body=%([\w.\-]+)"),
            ("branch", r"(?:true|false)_computation=%([\w.\-]+)"),
            ("call", r" call\(.*?to_apply=%([\w.\-]+)"))
    roles, todo = {}, [(entry, "entry")]
    while todo:
        name, role = todo.pop()
        if name in roles:
            continue
        roles[name] = role
        text = blocks[name]
        for kind, pattern in refs:
            todo += [(m.group(1), kind) for m in re.finditer(pattern, text)]
        for m in re.finditer(r"branch_computations=\{([^}]*)\}", text):
            todo += [(b, "branch") for b in re.findall(r"%([\w.\-]+)", m.group(1))]
    return roles


def launches(hlo_text: str) -> list[tuple[str, str, collections.Counter]]:
    """(role, name, Counter of the opcodes that launch) of each control computation, the
    most launches first."""
    blocks, _ = computations(hlo_text)
    rows = []
    for name, role in control_computations(hlo_text).items():
        ops = (_OPCODE.match(line) for line in blocks[name].split("\n")[1:])
        kinds = collections.Counter(m.group(1) for m in ops
                                    if m and m.group(1) not in NOT_LAUNCHED)
        rows.append((role, name, kinds))
    return sorted(rows, key=lambda r: (-sum(r[2].values()), r[1]))


def compile_only_sharding(target: Path):
    """A sharding on one compile-only CUDA device of the card ``target`` describes."""
    from jax.experimental import topologies

    topo = topologies.get_topology_desc(platform="cuda", target_config=target.read_text(),
                                        topology="1x1x1")
    mesh = topologies.make_mesh(topo, (1,), ("device",))
    return jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec())


def program_text(scene, camera, pipe, cfg, target: Path) -> str:
    """The optimized HLO text of ``pipe``'s images-only program on one frame of the scene,
    compiled for ``target``'s card."""
    from jaxrender.pipelines import program

    fixed, args, _ = program.arguments(pipe, scene, camera, cfg, outputs="images")
    sharding = compile_only_sharding(target)
    abstract = jax.tree.map(
        lambda a: jax.ShapeDtypeStruct(a.shape, a.dtype, sharding=sharding)
        if hasattr(a, "shape") and hasattr(a, "dtype") else a, args)
    return program.lower_arguments(fixed, abstract).compile().as_text()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("what", help="a pipeline name (forward, deferred, dacs, ...)")
    ap.add_argument("--scene", default="foliage")
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--shader-cost", type=int, default=None, metavar="N")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a config override, as profile_kernels.py takes it")
    ap.add_argument("--target", type=Path, default=TARGETS / "h100_sxm.txtpb",
                    help="the card, as a GpuTargetConfigProto in text form")
    ap.add_argument("--top", type=int, default=20, help="control computations listed")
    ap.add_argument("--dump", type=Path, default=None, help="write the optimized HLO here")
    a = ap.parse_args(argv)
    w, h = a.resolution
    scene, camera, pipe, cfg, label = pipeline_case(a.what, a.scene, w, h, a.set,
                                                    a.shader_cost)
    text = program_text(scene, camera, pipe, cfg, a.target)
    if a.dump:
        a.dump.write_text(text)
    rows = launches(text)
    total = sum((k for _, _, k in rows), collections.Counter())
    print(f"{label} on {a.target.stem} "
          f"(jax {jax.__version__}): {sum(total.values())} launching instructions in "
          f"{len(rows)} control computations, {dict(total.most_common())}")
    print("| launches | role | computation | by opcode |\n|---:|---|---|---|")
    for role, name, kinds in rows[:a.top]:
        print(f"| {sum(kinds.values())} | {role} | {name} | "
              f"{', '.join(f'{k} {n}' for k, n in kinds.most_common())} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
