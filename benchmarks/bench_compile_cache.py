"""Does the compile process pool still pay with JAX's persistent compilation cache on?

Runs a study four ways, each in a fresh process with its own cache folder: compile workers in
processes or in threads, from an empty cache (first run) and again with ``--force`` (every
reference and executable cached). Prints the wall time of each run and the study's own
"compiled or loaded ... in N s" line. Usage:

    python benchmarks/bench_compile_cache.py [--study studies/quickstart.toml] [--frames N]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

COMPILED = re.compile(r"compiled or loaded (\d+) program\(s\).* in ([\d.]+) s")


def one_run(study: str, out: Path, cache: Path, processes: bool, force: bool,
            extra: list[str]) -> dict:
    env = dict(os.environ, JAXRENDER_CACHE=str(cache),
               JAXRENDER_COMPILE_PROCESSES="1" if processes else "0")
    args = [sys.executable, "-m", "jaxrender", "study", study, "--out", str(out),
            "--no-progress", "--no-figures", *extra] + (["--force"] if force else [])
    start = time.perf_counter()
    done = subprocess.run(args, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode:
        raise SystemExit(f"{' '.join(args)} failed:\n{done.stdout}\n{done.stderr}")
    found = COMPILED.search(done.stdout + done.stderr)
    return {"wall_s": wall, "programs": int(found[1]) if found else None,
            "compile_phase_s": float(found[2]) if found else None}


def main() -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--study", default="studies/quickstart.toml")
    ap.add_argument("--frames", help="override every path's frame count")
    args = ap.parse_args()
    extra = ["--frames", args.frames] if args.frames else []
    print(f"study {args.study}; {os.cpu_count()} CPU cores")
    print(f"{'compile in':10s} {'cache':6s} {'programs':>8s} {'compile phase s':>15s} "
          f"{'wall s':>7s}")
    with tempfile.TemporaryDirectory() as tmp:
        for processes in (True, False):
            mode = "processes" if processes else "threads"
            cache, out = Path(tmp) / mode / "cache", Path(tmp) / mode / "run"
            for label, force in (("empty", False), ("warm", True)):
                r = one_run(args.study, out, cache, processes, force, extra)
                print(f"{mode:10s} {label:6s} {r['programs'] or '-':>8} "
                      f"{r['compile_phase_s'] or float('nan'):15.1f} {r['wall_s']:7.1f}",
                      flush=True)


if __name__ == "__main__":
    main()
