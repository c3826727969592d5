"""Time as the study, ``jaxrender bench`` and benchmarks/ measure it: compile timed apart (a
first call would mix it in), warm-up, ``block_until_ready`` (JAX dispatches asynchronously, so
a call returns before its work is done), several repeats and their median (a host's speed
drifts within a run), and the device recorded beside every number (a time means nothing
without it).
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import jax

from jaxrender.pipelines import program


def device_description() -> str:
    """The device the numbers come from: ``gpu:NVIDIA H200``, or for the CPU the processor
    and its core count, which is what a CPU time depends on."""
    dev = jax.devices()[0]
    kind = getattr(dev, "device_kind", "") or dev.platform
    if dev.platform == "cpu":
        kind = f"{platform.processor() or platform.machine()} ({os.cpu_count()} cores)"
    return f"{dev.platform}:{kind}"


def environment() -> dict:
    """Where the numbers were measured: recorded beside every study row and benchmark."""
    return {"device": device_description(), "jax_version": jax.__version__,
            "python": platform.python_version()}


@dataclass(frozen=True)
class Compiled:
    """A compiled pipeline program ready to time: ``call(scene, cameras) -> Frame`` (one
    camera, or a path for a sequence program). compile_ms is jax's lower + compile time,
    host-side preparation (object-space sheets) included; method is ``"aot"``, or
    ``"stored"`` for a program the study loaded from its executable store (compile_ms then
    the preparation and the load)."""

    call: Callable
    compile_ms: float
    method: str = "aot"


def compile_program(pipe, scene, cameras, cfg, *, sequence: bool = False,
                    warmup_frames: int = 0, outputs: str = "all") -> Compiled:
    """``pipe``'s single-frame program (``cameras`` one camera) or its sequence program over
    the path ``cameras``, compiled ahead of time (``pipelines.program.compile``), returning
    ``outputs`` (one of ``program.OUTPUTS``)."""
    call, ms = program.compile(pipe, scene, cameras, cfg, sequence=sequence,
                               warmup_frames=warmup_frames, outputs=outputs)
    return Compiled(call, ms)


def block(x):
    return jax.block_until_ready(x)


def time_call(fn: Callable, *args, repeats: int = 3, warmup: int = 0):
    """(result of the first timed call, median ms, every sample in ms)."""
    for _ in range(warmup):
        block(fn(*args))
    samples, out = [], None
    for i in range(max(1, repeats)):
        t0 = time.perf_counter()
        res = block(fn(*args))
        samples.append((time.perf_counter() - t0) * 1e3)
        if i == 0:
            out = res
    return out, statistics.median(samples), samples


def sample_stats(samples_ms: list[float]) -> dict:
    """Median, min, max and count of timed samples (ms)."""
    return {"median_ms": statistics.median(samples_ms), "min_ms": min(samples_ms),
            "max_ms": max(samples_ms), "repeats": len(samples_ms)}


def memory_analysis(compiled) -> dict:
    """MiB the compiled program asks for (arguments, outputs, temporaries), where known."""
    try:
        m = compiled.memory_analysis()
    except Exception:  # noqa: BLE001 - not every backend implements it
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
    and ``out`` (a result; pop it before printing), and with ``keep_compiled`` the
    compiled program as ``compiled``."""
    if not hasattr(fn, "lower"):
        fn = jax.jit(fn)
    t0 = time.perf_counter()
    compiled = fn.lower(*args, **static).compile()
    compile_s = time.perf_counter() - t0
    out, _, samples = time_call(compiled, *args, repeats=repeats, warmup=warmup)
    extra = {"compiled": compiled} if keep_compiled else {}
    return dict(sample_stats(samples), compile_s=compile_s, **memory_analysis(compiled), out=out,
                **extra)


def time_first_call(call: Callable[[], object], repeats: int = 10) -> dict:
    """Time a call that cannot be lowered as a whole (host-side checks, retries): the first
    call's time minus the steady median is reported as ``compile_s``."""
    t0 = time.perf_counter()
    block(call())
    first_ms = (time.perf_counter() - t0) * 1e3
    out, median, samples = time_call(call, repeats=repeats)
    return dict(sample_stats(samples), compile_s=max(first_ms - median, 0.0) / 1e3, out=out)


def time_interleaved(steps: dict[str, Callable], repeats: int, rounds: int = 10,
                     warmup: int = 3) -> tuple[dict, dict]:
    """Median ms of ``state = step(state)`` for each named step (the state starts as None:
    a frame loop can hand each frame's buffers to the next), the steps taking turns over
    ``rounds`` rounds of ``repeats // rounds`` calls: a call of well under a millisecond is
    host-bound, and the host's speed drifts within a run. Returns the medians and each
    step's last state."""
    state = dict.fromkeys(steps)
    for name, step in steps.items():
        for _ in range(warmup):
            state[name] = block(step(state[name]))
    samples = {name: [] for name in steps}
    for _ in range(rounds):
        for name, step in steps.items():
            for _ in range(max(1, repeats // rounds)):
                t0 = time.perf_counter()
                state[name] = block(step(state[name]))
                samples[name].append((time.perf_counter() - t0) * 1e3)
    return {name: statistics.median(v) for name, v in samples.items()}, state


def time_batched(fn: Callable, *args, calls: int, repeats: int = 3) -> float:
    """Median ms per call of ``calls`` calls dispatched back to back with one wait at the end:
    the throughput a loop that never waits for a frame reaches."""
    per = []
    for _ in range(repeats):
        block(fn(*args))
        t0 = time.perf_counter()
        outs = [fn(*args) for _ in range(calls)]
        block(outs)
        per.append((time.perf_counter() - t0) * 1e3 / calls)
        del outs
    return statistics.median(per)


def peak_memory() -> dict:
    """Peak and current MiB on device 0 since the process started (None where the backend
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
