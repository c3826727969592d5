"""How long does ``lex_sort`` take on keys shaped like the transparent composite's, and what does
XLA make of it?

The keys are a pixel of a 1920x1080 screen (21 bits) and a window depth's bits (30 bits), with
ties, and one entry in seven out of range (not in front), carrying a float32[N, 3] payload, as
``transparency.sorted_composite`` sorts them. Prints, per list length: the time per sort
(median of the repeats), and in the optimized program the sorts left as sorts and the
custom calls whose target names a sort (cub's radix sort on a GPU), with the distinct targets
listed under the table. Run it in each tree to compare (PYTHONPATH=TREE). Usage:

    python benchmarks/bench_lex_sort.py [--sizes 1000000 3110400] [--repeats 20]
"""

from __future__ import annotations

import argparse
import re
import statistics
import time

import jax
import numpy as np

from jaxrender.sorting import lex_sort

N_PIX, ONE_BITS = 1920 * 1080, 0x3F800000


def inputs(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    pixel = rng.integers(0, N_PIX, n).astype(np.int32)
    depth_bits = rng.integers(ONE_BITS - 2**20, ONE_BITS, n).astype(np.int32)
    pixel[::7], depth_bits[::7] = N_PIX, ONE_BITS + 1
    payload = rng.normal(size=(n, 3)).astype(np.float32)
    return tuple(jax.device_put(a) for a in (pixel, depth_bits, payload))


def sort_fn(pixel, order, payload):
    keys, (moved,) = lex_sort((pixel, order), (N_PIX - 1, ONE_BITS), (payload,))
    return keys[0], keys[1], moved


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", nargs="+", type=int, default=[1_000_000, 3_110_400])
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    fn = jax.jit(sort_fn)
    print(f"device {jax.devices()[0].device_kind}, jax {jax.__version__}")
    print("| entries | ms a sort | sorts | sort custom calls |")
    print("|---:|---:|---:|---:|")
    targets = set()
    for n in args.sizes:
        x = inputs(n)
        text = fn.lower(*x).compile().as_text()
        sorts = len(re.findall(r"\bsort\(", text))
        calls = re.findall(r'custom_call_target="([^"]*)"', text)
        targets.update(calls)
        cub = sum("sort" in c.lower() for c in calls)
        jax.block_until_ready(fn(*x))
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            jax.block_until_ready(fn(*x))
            times.append(time.perf_counter() - start)
        print(f"| {n} | {1e3 * statistics.median(times):.3f} | {sorts} | {cub} |", flush=True)
    print(f"custom-call targets: {sorted(targets) or 'none'}; program text {len(text)} chars")


if __name__ == "__main__":
    main()
