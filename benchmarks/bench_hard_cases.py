"""Every hard case (jaxrender/scene/hard_cases.py) through every registered pipeline: finite,
error against the reference within the case's bound, bitwise rerun. Writes the table (Markdown
and CSV) and a figure.

    python benchmarks/bench_hard_cases.py                      # the whole catalogue
    python benchmarks/bench_hard_cases.py --cases hard_sliver hard_flat --out /tmp/hc

The same ``evaluate`` drives tests/hard_cases/test_hard_pipelines.py. The reference is the
``reference`` pipeline at k = REF_K; error is the display-referred RMSE (``to_display``: clamp,
sRGB encode), as the studies report it.
"""

from __future__ import annotations

import argparse
import csv
import functools
import math
import sys
import time
from pathlib import Path

import jax
import numpy as np

REF_K = 4
COUNT_COLUMNS = ("shade_invocations", "covered_pixels", "helper_lanes", "overshading")
METRIC_NAMES = ("rmse", "psnr", "mssim", "flip", "delta_e")


@functools.lru_cache(maxsize=None)
def scene_of(case_name: str):
    from jaxrender.scene.hard_cases import CASES

    return CASES[case_name].build()


def pipeline_names() -> list[str]:
    from jaxrender.pipelines import list_pipelines

    return [p.name for p in list_pipelines()]


def render(case_name: str, pipeline: str, resolution) -> tuple[np.ndarray, dict]:
    """(image float32[H, W, 3], counts {name: float}) of one case through one pipeline."""
    from jaxrender.pipelines import get_pipeline, make_config

    scene = scene_of(case_name)
    w, h = resolution
    params = {"k": REF_K} if pipeline == "reference" else {}
    frame = get_pipeline(pipeline).render(scene, scene.camera,
                                          make_config(pipeline, width=w, height=h, **params))
    jax.block_until_ready(frame.image)
    counts = {k: float(np.asarray(v)) for k, v in frame.counts.items() if np.ndim(v) == 0}
    return np.asarray(frame.image), counts


@functools.lru_cache(maxsize=None)
def reference_image(case_name: str, resolution) -> np.ndarray:
    return render(case_name, "reference", resolution)[0]


def image_metrics(test: np.ndarray, ref: np.ndarray) -> dict:
    from jaxrender import metrics

    names = [n for n in METRIC_NAMES if n != "mssim" or min(test.shape[:2]) >= 11]
    vals = metrics.image_metrics(test, ref, names=tuple(names))
    return {k: float(np.asarray(v)) for k, v in vals.items()}


def evaluate(case_name: str, pipeline: str, resolution) -> dict:
    """One row: finiteness of image / counts / metrics, error vs the reference, rerun."""
    from jaxrender.scene.hard_cases import CASES

    case = CASES[case_name]
    t0 = time.perf_counter()
    img, counts = render(case_name, pipeline, resolution)
    first_s = time.perf_counter() - t0
    img2, counts2 = render(case_name, pipeline, resolution)
    ref = reference_image(case_name, tuple(resolution))
    finite_img = bool(np.all(np.isfinite(img)))
    finite_counts = all(math.isfinite(v) for v in counts.values())
    mets = image_metrics(img, ref) if finite_img else {}
    # PSNR is +inf exactly when the images are equal; every other value must be finite.
    finite_metrics = finite_img and all(
        math.isfinite(v) or (k == "psnr" and v == math.inf and mets["rmse"] == 0.0)
        for k, v in mets.items())
    w, h = resolution
    row = {
        "case": case_name, "pipeline": pipeline, "resolution": f"{w}x{h}",
        "finite": finite_img and finite_counts and finite_metrics,
        "finite_image": finite_img, "finite_counts": finite_counts,
        "finite_metrics": finite_metrics,
        "rmse": mets.get("rmse", math.nan), "bound": case.bound,
        "deterministic": bool(np.array_equal(img, img2, equal_nan=True) and counts == counts2),
        "first_s": first_s,
        **{k: mets.get(k, math.nan) for k in METRIC_NAMES if k != "rmse"},
        **{k: counts.get(k, math.nan) for k in COUNT_COLUMNS},
        "image_max": float(np.max(img)) if img.size else 0.0,
        "image_min": float(np.min(img)) if img.size else 0.0,
        "image_range": float(np.max(np.ptp(img.reshape(-1, 3), axis=0))) if img.size else 0.0,
    }
    row["within_bound"] = bool(row["rmse"] <= case.bound + 1e-7)
    return row


def run(cases=None, pipelines=None, progress=True) -> list[dict]:
    from jaxrender.scene.hard_cases import CASES

    rows = []
    for name in cases or list(CASES):
        for res in CASES[name].resolutions:
            for p in pipelines or pipeline_names():
                try:
                    row = evaluate(name, p, tuple(res))
                except Exception as e:  # a crash is a result too: report it, go on
                    row = {"case": name, "pipeline": p, "resolution": f"{res[0]}x{res[1]}",
                           "finite": False, "error": f"{type(e).__name__}: {e}"[:300]}
                rows.append(row)
                if progress:
                    print(_line(row), file=sys.stderr, flush=True)
    return rows


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else "NO"
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        if math.isinf(v):
            return "inf"
        return f"{v:.4g}"
    return str(v)


TABLE_COLUMNS = ("case", "pipeline", "resolution", "finite", "rmse", "bound", "within_bound",
                 "deterministic", "shade_invocations", "covered_pixels", "overshading")


def _line(row: dict) -> str:
    if "error" in row:
        return f"{row['case']:<20} {row['pipeline']:<13} {row['resolution']:<8} CRASH {row['error']}"
    return "  ".join(_fmt(row.get(c, math.nan)) for c in TABLE_COLUMNS)


def markdown(rows: list[dict]) -> str:
    out = ["| " + " | ".join(TABLE_COLUMNS) + " |", "|" + "---|" * len(TABLE_COLUMNS)]
    for r in rows:
        if "error" in r:
            out.append(f"| {r['case']} | {r['pipeline']} | {r['resolution']} | CRASH: "
                       f"{r['error']} |" + " |" * (len(TABLE_COLUMNS) - 4))
        else:
            out.append("| " + " | ".join(_fmt(r.get(c, math.nan)) for c in TABLE_COLUMNS) + " |")
    return "\n".join(out) + "\n"


def figure(rows: list[dict], path: Path) -> None:
    """Heat map: error / bound per (case, pipeline); crosses mark non-finite or failed rows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = sorted({(r["case"], r["resolution"]) for r in rows},
                  key=lambda k: [r["case"] for r in rows].index(k[0]))
    pipes = sorted({r["pipeline"] for r in rows})
    ratio = np.full((len(keys), len(pipes)), np.nan)
    bad = np.zeros_like(ratio, bool)
    for r in rows:
        i, j = keys.index((r["case"], r["resolution"])), pipes.index(r["pipeline"])
        ok = "error" not in r and r["finite"] and r["deterministic"]
        bad[i, j] = not ok
        if "error" not in r and math.isfinite(r.get("rmse", math.nan)):
            b = r["bound"]
            ratio[i, j] = r["rmse"] / b if b > 0 else (0.0 if r["rmse"] == 0 else 2.0)
    fig, ax = plt.subplots(figsize=(1.2 + 0.9 * len(pipes), 0.8 + 0.28 * len(keys)))
    im = ax.imshow(np.clip(ratio, 0, 2), cmap="RdYlGn_r", vmin=0, vmax=2, aspect="auto")
    for i, j in zip(*np.nonzero(bad)):
        ax.text(j, i, "x", ha="center", va="center", color="black", fontsize=10)
    ax.set_xticks(range(len(pipes)), pipes, rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(len(keys)), [f"{c} {res}" for c, res in keys], fontsize=7)
    fig.colorbar(im, ax=ax, label="display RMSE / case bound (x: non-finite or not bitwise)")
    ax.set_title("Hard cases vs reference", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120, metadata={"Software": None})
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--cases", nargs="*", help="case names (default: all)")
    ap.add_argument("--pipelines", nargs="*", help="pipelines (default: all registered)")
    ap.add_argument("--out", default="benchmarks/hard_cases", help="output directory")
    args = ap.parse_args(argv)
    jax.config.update("jax_numpy_rank_promotion", "raise")  # as the tests run
    jax.config.update("jax_numpy_dtype_promotion", "strict")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    rows = run(args.cases, args.pipelines)
    (out / "table.md").write_text(markdown(rows))
    cols = sorted({k for r in rows for k in r})
    with open(out / "table.csv", "w", newline="") as fh:
        wr = csv.DictWriter(fh, cols)
        wr.writeheader()
        wr.writerows(rows)
    figure(rows, out / "hard_cases.png")
    bad = [r for r in rows if "error" in r or not (r["finite"] and r["deterministic"]
                                                    and r["within_bound"])]
    print(f"{len(rows)} rows, {len(bad)} failing, {time.perf_counter() - t0:.0f} s; "
          f"wrote {out}/table.md, table.csv, hard_cases.png", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
