"""Benchmark jaxrender.metrics against the reference libraries, in one run, on any device.

Each metric is timed on RGB frames (default 1920x1080), one frame and a batch of --frames
(default 60), through the public API (input checks included). JAX: one warm-up call (its time
minus the steady median is reported as compile time), then --repeats timed calls with
block_until_ready, median reported. Libraries (scikit-image, flip-evaluator, colour-science,
NumPy) run frame by frame on the host on --lib-frames frames, median per frame reported.

    python benchmarks/bench_metrics.py                          # GPU: full 1080p, 60 frames
    JAX_PLATFORMS=cpu python benchmarks/bench_metrics.py --frames 4 --repeats 3 --lib-frames 1
"""

from __future__ import annotations

import argparse
import statistics

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender import metrics
from jaxrender.parsing import help_summary
from jaxrender.timing import environment, time_call, time_first_call


def _time_jax(fn, repeats):
    """(median s, compile s: the first call's time minus the median)."""
    r = time_first_call(fn, repeats)
    return r["median_ms"] / 1e3, r["compile_s"]


def _time_lib(fn, frames, repeats):
    """The median s of one host call over ``frames`` frames, ``repeats`` rounds."""
    samples = [ms for _ in range(repeats) for t in range(frames)
               for ms in time_call(fn, t, repeats=1)[2]]
    return statistics.median(samples) / 1e3


def _library_calls(ref_np, test_np):
    """Per-frame reference-library calls, keyed like the JAX cases."""
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    calls = {
        "psnr": ("skimage psnr", lambda t: peak_signal_noise_ratio(ref_np[t], test_np[t],
                                                                   data_range=1.0)),
        "ssim": ("skimage ssim (gaussian)", lambda t: structural_similarity(
            ref_np[t], test_np[t], data_range=1.0, channel_axis=-1, gaussian_weights=True,
            sigma=1.5, use_sample_covariance=False)),
        "ssim_uniform7": ("skimage ssim (default)", lambda t: structural_similarity(
            ref_np[t], test_np[t], data_range=1.0, channel_axis=-1)),
    }
    try:
        import flip_evaluator

        def flip_call(mode, scale):
            def call(t):
                r = np.ascontiguousarray(ref_np[t] * scale, np.float32)  # copies: it works in place
                s = np.ascontiguousarray(test_np[t] * scale, np.float32)
                return flip_evaluator.evaluate(r, s, mode, applyMagma=False)
            return call

        calls["flip_ldr"] = ("flip_evaluator LDR", flip_call("LDR", 1.0))
        calls["flip_hdr"] = ("flip_evaluator HDR", flip_call("HDR", 4.0))
    except ImportError:
        pass
    try:
        import colour

        def de(t):
            lab1 = colour.XYZ_to_Lab(colour.sRGB_to_XYZ(ref_np[t].astype(np.float64)))
            lab2 = colour.XYZ_to_Lab(colour.sRGB_to_XYZ(test_np[t].astype(np.float64)))
            return colour.delta_E(lab1, lab2, method="CIE 2000")

        calls["delta_e2000"] = ("colour delta_E CIE 2000", de)
    except ImportError:
        pass
    return calls


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=help_summary(__doc__))
    p.add_argument("--width", type=int, default=1920)
    p.add_argument("--height", type=int, default=1080)
    p.add_argument("--frames", type=int, default=60, help="batch size (0: skip batched)")
    p.add_argument("--repeats", type=int, default=10)
    p.add_argument("--lib-frames", type=int, default=2, help="frames timed per library (0: skip)")
    p.add_argument("--lib-repeats", type=int, default=1)
    p.add_argument("--dtype", choices=("float32", "float64"), default="float32")
    p.add_argument("--impl", choices=("slices", "conv"), default=metrics.correlate_impl(),
                   help="separable filter implementation (SSIM, FLIP)")
    p.add_argument("--only", nargs="*", default=None, help="subset of metric keys")
    return p.parse_args(argv)


def frames(w: int, h: int, n: int):
    """(reference, test) batches of n random (h, w, 3) frames, the test a clipped noisy copy,
    and the (n - 1) sample positions a warp error reads the test at."""
    key_a, key_b = jax.random.split(jax.random.PRNGKey(0))
    ref = jax.random.uniform(key_a, (n, h, w, 3), jnp.float32)
    test = jnp.clip(ref + 0.05 * jax.random.normal(key_b, (n, h, w, 3), jnp.float32), 0.0, 1.0)
    jax.block_until_ready((ref, test))
    pos = jnp.broadcast_to(
        jnp.stack(jnp.meshgrid(jnp.arange(w) + 0.5, jnp.arange(h) + 0.5), -1) + 0.25,
        (max(n - 1, 1), h, w, 2)).astype(jnp.float32)
    return ref, test, pos


def metric_cases(dtype, pos, only) -> tuple[dict, dict]:
    """The per-image and the sequence metrics timed, as ``fn(reference, test)``."""
    cases = {
        "psnr": lambda r, t: metrics.psnr(r, t, dtype=dtype),
        "ssim": lambda r, t: metrics.ssim(r, t, dtype=dtype),
        "ssim_uniform7": lambda r, t: metrics.ssim(r, t, window="uniform7", dtype=dtype),
        "flip_ldr": lambda r, t: metrics.flip(r, t, dtype=dtype),
        "flip_hdr": lambda r, t: metrics.flip(4.0 * r, 4.0 * t, "hdr", dtype=dtype),
        "delta_e2000": lambda r, t: metrics.delta_e2000(r, t, dtype=dtype),
    }
    seq_cases = {
        "temporal_error": lambda r, t: metrics.temporal_error(t, r, dtype=dtype),
        "warp_error": lambda r, t: metrics.warp_error(t, r, pos[: r.shape[0] - 1], dtype=dtype),
    }
    if only:
        cases = {k: v for k, v in cases.items() if k in only}
        seq_cases = {k: v for k, v in seq_cases.items() if k in only}
    return cases, seq_cases


def jax_rows(cases, seq_cases, ref, test, args) -> list[tuple]:
    """(metric, "jaxrender", frames, compile s, ms per call, ms per frame) of one frame and of
    the batch; the sequence metrics on the batch only."""
    n = ref.shape[0]
    ref1, test1 = ref[0], test[0]  # sliced once, outside the timed calls
    rows = []
    for name, fn in cases.items():
        med, comp = _time_jax(lambda: fn(ref1, test1), args.repeats)
        rows.append((name, "jaxrender", "1", comp, med * 1e3, med * 1e3))
        if args.frames > 0:
            med, comp = _time_jax(lambda: fn(ref, test), args.repeats)
            rows.append((name, "jaxrender", str(n), comp, med * 1e3, med * 1e3 / n))
        print(f"  {name}: done", flush=True)
    for name, fn in seq_cases.items():
        if args.frames > 1:
            med, comp = _time_jax(lambda: fn(ref, test), args.repeats)
            rows.append((name, "jaxrender", str(n), comp, med * 1e3, med * 1e3 / (n - 1)))
    return rows


def library_rows(cases, ref, test, args) -> list[tuple]:
    """The reference libraries' rows, frame by frame on the host, for the metrics timed."""
    rows = []
    k = min(args.lib_frames, ref.shape[0])
    ref_np, test_np = np.asarray(ref[:k]), np.asarray(test[:k])
    for name, (label, call) in _library_calls(ref_np, test_np).items():
        if name in cases:
            per = _time_lib(call, k, args.lib_repeats)
            rows.append((name, label, "1", float("nan"), per * 1e3, per * 1e3))
            print(f"  {label}: done", flush=True)
    return rows


def print_rows(rows, w: int, h: int, repeats: int) -> None:
    lib_per_frame = {r[0]: r[5] for r in rows if r[1] != "jaxrender"}
    print(f"\n{w}x{h} RGB, {repeats} repeats (median), compile = first call - median\n")
    print("| metric | implementation | frames | compile (s) | median per call (ms) "
          "| per frame (ms) | speed-up vs library |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name, impl, n_frames, comp, call_ms, frame_ms in rows:
        comp_s = "" if np.isnan(comp) else f"{comp:.2f}"
        lib = lib_per_frame.get(name)
        speed = f"{lib / frame_ms:.1f}x" if lib and impl == "jaxrender" else ""
        print(f"| {name} | {impl} | {n_frames} | {comp_s} | {call_ms:.2f} | {frame_ms:.2f} "
              f"| {speed} |")


def main(argv=None):
    args = parse_args(argv)
    metrics.set_correlate_impl(args.impl)
    dtype = np.dtype(args.dtype)
    env = environment()
    print(f"{env['device']}, jax {env['jax_version']}, dtype {dtype}, filters {args.impl}")
    w, h = args.width, args.height
    ref, test, pos = frames(w, h, max(args.frames, 1))
    cases, seq_cases = metric_cases(dtype, pos, args.only)
    rows = jax_rows(cases, seq_cases, ref, test, args)
    if args.lib_frames > 0:
        rows += library_rows(cases, ref, test, args)
    print_rows(rows, w, h, args.repeats)


if __name__ == "__main__":
    main()
