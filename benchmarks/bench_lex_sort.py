"""How long does ``lex_sort`` take on keys shaped like a pipeline's, and what does XLA make of
it?

``--keys composite`` (the default): a pixel of a 1920x1080 screen (21 bits) and a window
depth's bits (30 bits), as ``transparency.sorted_composite`` sorts them; ``--keys quads``:
forward's quad, triangle and lane (19 + 10 + 3 bits). Both with ties, one entry in seven out
of range, and a float32[N, 3] payload carried. Prints, per list length: the time per sort
(median of the repeats), and in the optimized program the sorts left as sorts and the
custom calls whose target names a sort (cub's radix sort on a GPU), with the distinct targets
listed under the table. Run it in each tree to compare (PYTHONPATH=TREE). Usage:

    python benchmarks/bench_lex_sort.py [--keys quads] [--sizes 1000000 3110400] [--repeats 20]
"""

from __future__ import annotations

import argparse
import re
import statistics
import time

import jax
import numpy as np

from jaxrender.parsing import help_summary
from jaxrender.sorting import lex_sort

N_PIX, ONE_BITS = 1920 * 1080, 0x3F800000
N_QUADS, N_TRIS = 960 * 540, 1000
# Each kind of key: its limits, as the pipeline passes them to lex_sort.
LIMITS = {"composite": (N_PIX - 1, ONE_BITS), "quads": (N_QUADS - 1, N_TRIS - 1, 3)}


def inputs(kind: str, n: int, seed: int = 0):
    """Keys of ``kind`` with ties and one entry in seven out of range, and a float32[n, 3]
    payload: "composite" a pixel and a window depth's bits (the transparent composite's),
    "quads" forward's quad, triangle and lane (19 + 10 + 3 bits at 1080p)."""
    rng = np.random.default_rng(seed)
    if kind == "composite":
        keys = [rng.integers(0, N_PIX, n), rng.integers(ONE_BITS - 2**20, ONE_BITS, n)]
    else:
        keys = [rng.integers(0, lim + 1, n) for lim in LIMITS[kind]]
    keys = [k.astype(np.int32) for k in keys]
    for k, lim in zip(keys, LIMITS[kind]):
        k[::7] = lim + 1
    payload = rng.normal(size=(n, 3)).astype(np.float32)
    return tuple(jax.device_put(a) for a in (*keys, payload))


def sort_fn(kind: str):
    def fn(*args):
        keys, (moved,) = lex_sort(args[:-1], LIMITS[kind], (args[-1],))
        return (*keys, moved)

    return fn


def main() -> None:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--sizes", nargs="+", type=int, default=[1_000_000, 3_110_400])
    ap.add_argument("--keys", choices=sorted(LIMITS), default="composite")
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    fn = jax.jit(sort_fn(args.keys))
    print(f"device {jax.devices()[0].device_kind}, jax {jax.__version__}, keys {args.keys}")
    print("| entries | ms a sort | sorts | sort custom calls |")
    print("|---:|---:|---:|---:|")
    targets = set()
    for n in args.sizes:
        x = inputs(args.keys, n)
        text = fn.lower(*x).compile().as_text()
        sorts = len(re.findall(r"\bsort\(", text))
        calls = re.findall(r'custom_call_target="([^"]*)"', text)
        targets.update(calls)
        sort_calls = sum("sort" in c.lower() for c in calls)
        jax.block_until_ready(fn(*x))
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            jax.block_until_ready(fn(*x))
            times.append(time.perf_counter() - start)
        ms = 1e3 * statistics.median(times)
        print(f"| {n} | {ms:.3f} | {sorts} | {sort_calls} |", flush=True)
    print(f"custom-call targets: {sorted(targets) or 'none'}; program text {len(text)} chars")


if __name__ == "__main__":
    main()
