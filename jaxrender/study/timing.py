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
    """A compiled pipeline program ready to time: ``call(scene, cameras) -> Frame`` (one
    camera, or a path for a sequence program). compile_ms is jax's lower + compile time,
    host-side preparation (object-space sheets) included; method is ``"aot"``."""

    call: Callable
    compile_ms: float
    method: str = "aot"


def compile_program(pipe, scene, cameras, cfg, *, sequence: bool = False,
                    warmup_frames: int = 0) -> Compiled:
    """``pipe``'s single-frame program (``cameras`` one camera) or its sequence program over
    the path ``cameras``, compiled ahead of time (``pipelines.program.compile``)."""
    from jaxrender.pipelines import program

    call, ms = program.compile(pipe, scene, cameras, cfg, sequence=sequence,
                               warmup_frames=warmup_frames)
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
