"""Honest time for benchmarks (DESIGN.md principle 8): compile apart, warm-up,
block_until_ready, several repeats, median; the device and memory recorded beside each number.

The same recipe as ``benchmarks/common.py``, inside the package so that ``jaxrender bench``
needs nothing outside it.
"""

from __future__ import annotations

import datetime
import json
import platform
import statistics
import time
from collections.abc import Callable

import jax


def environment() -> dict:
    """Where and when the numbers were measured."""
    d = jax.devices()[0]
    kind = getattr(d, "device_kind", "") or d.platform
    return {
        "device": f"{d.platform}:{kind} x{jax.device_count()}",
        "jax": jax.__version__,
        "python": platform.python_version(),
        "date": datetime.date.today().isoformat(),
        "host": platform.node(),
    }


def _stats(samples_s: list[float]) -> dict:
    return {
        "median_ms": 1e3 * statistics.median(samples_s),
        "min_ms": 1e3 * min(samples_s),
        "max_ms": 1e3 * max(samples_s),
        "repeats": len(samples_s),
    }


def memory_analysis(compiled) -> dict:
    """Bytes the compiled program asks for (arguments, outputs, temporaries), where known."""
    try:
        m = compiled.memory_analysis()
    except Exception:  # noqa: BLE001 - not every backend implements it
        return {}
    if m is None:
        return {}
    out = {}
    for key in ("argument_size_in_bytes", "output_size_in_bytes", "temp_size_in_bytes"):
        v = getattr(m, key, None)
        if v is not None:
            out[key.replace("_size_in_bytes", "_mib")] = v / 2**20
    return out


def time_compiled(fn, *args, repeats: int = 10, warmup: int = 2, keep_compiled: bool = False,
                  **static) -> dict:
    """AOT-compile ``fn`` (jitted, or jitted here) for ``args`` and time steady-state calls.

    Returns median/min/max ms, ``compile_s`` (lower + compile), the program's memory analysis
    and ``out`` (the last result; pop it before printing), and with ``keep_compiled`` the
    compiled program as ``compiled``."""
    if not hasattr(fn, "lower"):
        fn = jax.jit(fn)
    t0 = time.perf_counter()
    compiled = fn.lower(*args, **static).compile()
    compile_s = time.perf_counter() - t0
    out = None
    for _ in range(warmup):
        out = jax.block_until_ready(compiled(*args))
    samples = []
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = jax.block_until_ready(compiled(*args))
        samples.append(time.perf_counter() - t0)
    extra = {"compiled": compiled} if keep_compiled else {}
    return dict(_stats(samples), compile_s=compile_s, **memory_analysis(compiled), out=out, **extra)


def time_first_call(call: Callable[[], object], repeats: int = 10) -> dict:
    """Time a call that cannot be lowered as a whole (host-side checks, retries): the first
    call's time minus the steady median is reported as ``compile_s``."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(call())
    first = time.perf_counter() - t0
    samples = []
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = jax.block_until_ready(call())
        samples.append(time.perf_counter() - t0)
    st = _stats(samples)
    return dict(st, compile_s=max(first - st["median_ms"] / 1e3, 0.0), out=out)


def peak_memory() -> dict:
    """Peak and current bytes on device 0 since the process started (None where the backend
    keeps no statistics, as the CPU does). JAX cannot reset the peak, so a section's peak is
    the largest of everything run before it too."""
    try:
        s = jax.devices()[0].memory_stats() or {}
    except Exception:  # noqa: BLE001 - no statistics on this backend
        s = {}
    def mib(k):
        return (s[k] / 2**20) if k in s else None

    return {"peak_mib": mib("peak_bytes_in_use"), "in_use_mib": mib("bytes_in_use"),
            "limit_mib": mib("bytes_limit")}


def fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1e-2 or abs(v) >= 1e5 else f"{v:.3f}"
    return "" if v is None else str(v)


def print_table(rows: list[dict], columns: list[str], file=None) -> None:
    print("| " + " | ".join(columns) + " |", file=file)
    print("|" + "|".join("---" for _ in columns) + "|", file=file)
    for r in rows:
        print("| " + " | ".join(fmt(r.get(c)) for c in columns) + " |", file=file, flush=True)


def dump(path, payload: dict) -> None:
    if path:
        with open(path, "w") as fh:
            json.dump(payload, fh, indent=1, default=str)
