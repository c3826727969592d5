"""Metric times through the public API (input checks included), one frame and a batch.

The full comparison against scikit-image, flip-evaluator and colour-science is
``benchmarks/bench_metrics.py``; this section times jaxrender's side only."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrender.timing import time_first_call


def _cases():
    from jaxrender import metrics

    return {
        "psnr": lambda r, t: metrics.psnr(r, t),
        "ssim": lambda r, t: metrics.ssim(r, t),
        "flip": lambda r, t: metrics.flip(r, t),
        "delta_e2000": lambda r, t: metrics.delta_e2000(r, t),
        "temporal_error": lambda r, t: metrics.temporal_error(t, r),
    }


def time_metrics(width: int, height: int, frames: int, repeats: int = 5):
    """Yield one row per (metric, batch size)."""
    ka, kb = jax.random.split(jax.random.PRNGKey(0))
    n = max(frames, 2)
    ref = jax.random.uniform(ka, (n, height, width, 3), jnp.float32)
    test = jnp.clip(ref + 0.05 * jax.random.normal(kb, ref.shape, jnp.float32), 0.0, 1.0)
    jax.block_until_ready((ref, test))
    for name, fn in _cases().items():
        sizes = [n] if name == "temporal_error" else [1, frames] if frames > 1 else [1]
        for t in sizes:
            row = dict(metric=name, resolution=f"{width}x{height}", frames=t)
            try:
                r_, t_ = (ref[0], test[0]) if t == 1 and name != "temporal_error" else (ref[:t], test[:t])
                r = time_first_call(lambda fn=fn, r_=r_, t_=t_: fn(r_, t_), repeats)
                r.pop("out")
                row.update(r, per_frame_ms=r["median_ms"] / t)
            except Exception as e:  # noqa: BLE001
                row["skipped"] = f"{type(e).__name__}: {e}"[:200]
            yield row


COLUMNS = ["metric", "resolution", "frames", "median_ms", "per_frame_ms", "compile_s", "skipped"]
