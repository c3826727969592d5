"""Honest time (DESIGN.md principle 8): compile apart, warm-up, block_until_ready, median."""

from __future__ import annotations

import os
import platform
import statistics
import time
from dataclasses import dataclass
from typing import Callable

import jax


@dataclass(frozen=True)
class Compiled:
    """A render function ready to time: ``call(scene, camera) -> Frame``.

    method is ``"aot"`` when compile_ms is jax's lower+compile time, or ``"first_call"`` when
    the pipeline could not be lowered as a whole and compile_ms is the first call's time minus
    the steady-state median (filled in by the runner after timing)."""

    call: Callable
    compile_ms: float
    method: str


def compile_render(render: Callable, scene, camera, cfg) -> Compiled:
    """jit ``render(scene, camera, cfg)`` with cfg static and compile it ahead of time.

    A pipeline with host-side preparation per scene (object-space charts) provides
    ``render.compile_aot(scene, camera, cfg) -> call``; its compile time includes that
    preparation, done once per scene."""
    aot = getattr(render, "compile_aot", None)
    if aot is not None:
        t0 = time.perf_counter()
        call = aot(scene, camera, cfg)
        return Compiled(call, (time.perf_counter() - t0) * 1e3, "aot")
    jitted = jax.jit(render, static_argnums=2)
    t0 = time.perf_counter()
    try:
        compiled = jitted.lower(scene, camera, cfg).compile()
    except Exception:  # a pipeline with host-side steps (capacities, retries) cannot be lowered
        return Compiled(lambda s, c: render(s, c, cfg), float("nan"), "first_call")
    ms = (time.perf_counter() - t0) * 1e3
    return Compiled(lambda s, c: compiled(s, c), ms, "aot")


def _block(x):
    return jax.block_until_ready(x)


def time_call(fn: Callable, *args, repeats: int = 3, warmup: int = 0):
    """(result of the first timed call, median ms, every sample in ms)."""
    for _ in range(warmup):
        _block(fn(*args))
    samples, out = [], None
    for i in range(max(1, repeats)):
        t0 = time.perf_counter()
        res = _block(fn(*args))
        samples.append((time.perf_counter() - t0) * 1e3)
        if i == 0:
            out = res
    return out, statistics.median(samples), samples


def device_info() -> dict:
    """Where the numbers were measured: recorded beside every row and figure."""
    dev = jax.devices()[0]
    kind = getattr(dev, "device_kind", "") or dev.platform
    if dev.platform == "cpu":
        kind = f"{platform.processor() or platform.machine()} ({os.cpu_count()} cores)"
    return {
        "device": f"{dev.platform}:{kind}",
        "jax_version": jax.__version__,
        "python": platform.python_version(),
    }
