"""DACS against checkerboard (Mallett and Yuksel, HPG 2018, Table 1, deferred renderer scene),
measured by the bundled ``dacs_vs_checkerboard`` study.

The paper's table compares checkerboard with DACS at equal quality (checkerboard's MSSIM) and
at equal time: RMSE, PSNR, MSSIM against the fully shaded ground truth and the speed-up over
it. The study's matched points are those rows (``dacs_equal_quality``, ``dacs_equal_time``),
beside DACS at checkerboard's shading count (temporal and spatial-only checkerboard).

Time. ``speed-up`` is measured: deferred's time_ms over the pipeline's (our JAX DACS shades
each level's compacted pixels in chunks). ``warp`` beside it times the paper's warp scheme as
a GPU would spend it: every SHADE SIMD step is a full warp of the shader whatever its lanes
hold, at the ms per launched shading lane that the threshold sweep itself measures (the
least-squares line of DACS's time against its launched lanes, ``dispatch_lanes``, over the
sweep of that scene and path; its intercept is the fixed cost of visibility, the similarity
tests and the five dependent levels, which the warp scheme pays as well):
warp ms = intercept + slope * warp_width * warp_shade_steps. The claims use the measured time.

The absolute numbers belong to the paper's scene, not ours: they are set beside ours with a
10% tolerance and no direction. The claims that carry over are the relations: DACS faster than
checkerboard at equal quality (2.24x) and better than it at equal time (+13.3 dB PSNR).
"""

from __future__ import annotations

import dataclasses
import math

from jaxrender.pipelines.dacs import DacsConfig
from jaxrender.seeds.claim import REPRODUCED, Claim
from jaxrender.seeds.rows import sequence_means
from jaxrender.study.time_fit import fit_line

SOURCE = "DACS (Mallett and Yuksel 2018)"
FIGURE = "Table 1 (deferred renderer scene)"
STUDY = "dacs_vs_checkerboard"
TABLE_STEM = "dacs_table"  # dacs_table.md and dacs_table.csv in the run directory

QUALITY = ("rmse", "psnr", "mssim")
# Paper rows -> our labels, and the published values (speed-up over ground truth; the paper's
# equal-time DACS runs in checkerboard's time, so its speed-up is checkerboard's by construction).
PUBLISHED = {
    "checkerboard": {"rmse": 0.04218, "psnr": 27.53, "mssim": 0.8954, "speedup": 1.89},
    "dacs_equal_quality": {"rmse": 0.02647, "psnr": 31.57, "mssim": 0.8881, "speedup": 4.22},
    "dacs_equal_time": {"rmse": 0.009076, "psnr": 40.85, "mssim": 0.9620, "speedup": 1.89},
}
SPEEDUP_OVER_CHECKERBOARD = 2.24  # DACS at equal quality
# The table's rows: the paper's three, and DACS at equal count beside them.
TABLE_ROWS = ("checkerboard", "checkerboard_spatial", "dacs_equal_count",
              "dacs_equal_count_spatial", "dacs_equal_quality", "dacs_equal_time")
GROUND_TRUTH = "deferred"
SWEEP = "dacs"
# Relative tolerances of the absolute values (the paper's scene is not ours: they agree only
# by chance): MSSIM's is tight because its range near 1 is narrow, PSNR's about 1.4 dB.
ABSOLUTE_TOL = {"rmse": 0.10, "psnr": 0.05, "mssim": 0.01, "speedup": 0.10}
RELATION_TOL = 0.25
ABSOLUTE_REASON = ("the paper's scene is not ours: absolute quality and speed-up depend on "
                   "the scene and renderer; the relations below are the claims that carry over")


def _cases(means: list[dict]) -> dict:
    """{(scene, path): {label: sequence means}}; the sweep's points under (label, threshold)."""
    out: dict = {}
    for m in means:
        case = out.setdefault((m["scene"], m["camera_path"]), {})
        if m["pipeline"] == SWEEP:
            case.setdefault(SWEEP, []).append(m)
        else:
            case[m["pipeline"]] = m
    return out


def warp_fit(sweep: list[dict]):
    """time_ms against launched shading lanes over the sweep's points; None where no line
    says what a lane costs (the launched lanes do not vary, as at a tiny resolution where
    every level fits one chunk, or the slope is not positive: noise above the work)."""
    pts = [(m.get("dispatch_lanes"), m.get("time_ms")) for m in sweep]
    pts = [(x, y) for x, y in pts if isinstance(x, float) and isinstance(y, float)]
    try:
        fit = fit_line([x for x, _ in pts], [y for _, y in pts])
    except ValueError:
        return None
    return fit if fit.slope_ms > 0 else None


def warp_ms(m: dict, fit) -> float:
    """The warp scheme's frame time (module docstring); NaN where it does not apply."""
    steps = m.get("warp_shade_steps")
    if fit is None or not isinstance(steps, float):
        return math.nan
    width = int(m["params"].get("warp_width", DacsConfig.warp_width))
    return float(fit.predict(width * steps))


def table_rows(rows: list[dict]) -> list[dict]:
    """The paper's table for every scene and path of a run: one dict per (case, row)."""
    out = []
    for (scene, path), case in sorted(_cases(sequence_means(rows)).items()):
        truth = case.get(GROUND_TRUTH)
        fit = warp_fit(case.get(SWEEP, []))
        for label in TABLE_ROWS:
            m = case.get(label)
            if m is None or truth is None:
                continue
            t_warp = warp_ms(m, fit) if label.startswith("dacs") else math.nan
            out.append({
                "scene": scene, "camera_path": path, "pipeline": label,
                "threshold": m["params"].get("threshold", math.nan),
                "shaded": m["shade_invocations"] / max(m.get("covered_pixels", 0.0), 1.0),
                **{k: m.get(k, math.nan) for k in QUALITY},
                "time_ms": m["time_ms"], "speedup": truth["time_ms"] / m["time_ms"],
                "warp_ms": t_warp, "speedup_warp": truth["time_ms"] / t_warp,
                "match_reached": m.get("match_reached", True),
                **{f"published_{k}": PUBLISHED.get(label, {}).get(k, math.nan)
                   for k in (*QUALITY, "speedup")},
            })
    return out


def warp_fits(rows: list[dict]) -> dict:
    """{(scene, path): the sweep's line of time against launched lanes, or None}."""
    return {case: warp_fit(c.get(SWEEP, []))
            for case, c in sorted(_cases(sequence_means(rows)).items())}


def format_fits(fits: dict) -> str:
    lines = []
    for (scene, path), fit in fits.items():
        line = ("no line (the sweep's launched lanes do not vary, or time falls with them): "
                "no warp time" if fit is None else
                f"{fit.intercept_ms:.3f} ms + {fit.slope_ms:.3f} ms per million lanes, "
                f"R^2 {fit.r2:.3f}, {fit.n} points")
        lines.append(f"- {scene}, {path}: {line}")
    return "\n".join(lines)


def table_notes(rows: list[dict]) -> str:
    """What the warp time of each scene and path was read off."""
    return ("Warp time: time_ms against launched shading lanes over the threshold sweep, per "
            "scene and path:\n" + format_fits(warp_fits(rows)))


def format_table(table: list[dict]) -> str:
    """The table as Markdown (published values in brackets beside ours)."""
    head = ("| scene | path | pipeline | threshold | shaded | RMSE | PSNR | MSSIM | ms "
            "| speed-up (measured) | speed-up (warp) |")
    lines = [head, "|" + "---|" * 11]
    fmt = {"rmse": "{:.5f}", "psnr": "{:.2f}", "mssim": "{:.4f}", "speedup": "{:.2f}x"}

    def cell(r, k):
        ours = fmt[k].format(r[k])
        pub = r[f"published_{k}"]
        return ours if math.isnan(pub) else f"{ours} [{fmt[k].format(pub)}]"

    for r in table:
        thr = "" if math.isnan(r["threshold"]) else f"{r['threshold']:.3g}"
        note = "" if r["match_reached"] else " (not reached)"
        warp = "" if math.isnan(r["speedup_warp"]) else f"{r['speedup_warp']:.2f}x"
        lines.append(f"| {r['scene']} | {r['camera_path']} | {r['pipeline']}{note} | {thr} | "
                     f"{r['shaded']:.1%} | {cell(r, 'rmse')} | {cell(r, 'psnr')} | "
                     f"{cell(r, 'mssim')} | {r['time_ms']:.2f} | {cell(r, 'speedup')} | "
                     f"{warp} |")
    return "\n".join(lines) + (
        "\n\n[published] Mallett and Yuksel 2018, Table 1, deferred renderer scene. Quality "
        "against the fully shaded frame (deferred); speed-up over it, measured (time_ms); "
        "warp: the warp scheme's SHADE steps as full warps (jaxrender.seeds.dacs).\n")


# ------------------------------------------------------------------ claims


def _absolute(label: str, r: dict, cond: str) -> list[Claim]:
    name = {"checkerboard": "checkerboard", "dacs_equal_quality": "DACS at equal quality",
            "dacs_equal_time": "DACS at equal time"}[label]
    units = {"rmse": "RMSE", "psnr": "PSNR (dB)", "mssim": "MSSIM",
             "speedup": "speed-up over ground truth"}
    out = []
    for k in (*QUALITY, "speedup"):
        if label == "dacs_equal_time" and k == "speedup":
            continue  # checkerboard's by construction: the match's target, not a finding
        c = Claim(SOURCE, FIGURE, f"{name}: {units[k]}", PUBLISHED[label][k], r[k], cond,
                  ABSOLUTE_TOL[k], baseline=1.0 if k == "speedup" else None)
        if c.verdict != REPRODUCED:
            c = dataclasses.replace(c, reason=ABSOLUTE_REASON)
        out.append(c)
    return out


def _relations(rows: dict, cond: str) -> list[Claim]:
    cb, eq_q, eq_t = (rows.get(k) for k in ("checkerboard", "dacs_equal_quality",
                                            "dacs_equal_time"))
    out = []
    if cb and eq_q:
        ratio = cb["time_ms"] / eq_q["time_ms"]
        why = "" if ratio > 1 else (
            f"to reach checkerboard's MSSIM ({cb['mssim']:.4f}) DACS shades "
            f"{eq_q['shaded']:.0%} of the covered pixels (checkerboard {cb['shaded']:.0%}) and "
            f"takes {eq_q['time_ms']:.2f} ms against {cb['time_ms']:.2f} ms" + (
                "; fewer pixels in more time: DACS pays five dependent levels, each a "
                "decision pass and a launch, where checkerboard shades in one"
                if eq_q["shaded"] <= cb["shaded"] else
                "; checkerboard's half of the pixels (and, when temporal, its history) "
                "already reconstruct this scene as well as DACS does with more"))
        if not eq_q["match_reached"]:
            why = (f"no threshold gives checkerboard's MSSIM ({cb['mssim']:.4f}); the closest, "
                   f"{eq_q['threshold']:.3g}, gives {eq_q['mssim']:.4f}; " + why).rstrip("; ")
        out.append(Claim(SOURCE, FIGURE, "DACS speed-up over checkerboard at equal quality",
                         SPEEDUP_OVER_CHECKERBOARD, ratio, cond, RELATION_TOL, baseline=1.0,
                         reason=why))
    if cb and eq_t:
        gain = eq_t["psnr"] - cb["psnr"]
        pub = PUBLISHED["dacs_equal_time"]["psnr"] - PUBLISHED["checkerboard"]["psnr"]
        why = "" if gain > 0 else (
            f"at checkerboard's time ({cb['time_ms']:.2f} ms) DACS shades {eq_t['shaded']:.0%}"
            f" of the covered pixels and reaches {eq_t['psnr']:.2f} dB, checkerboard "
            f"{cb['psnr']:.2f} dB")
        if not eq_t["match_reached"] and eq_t["time_ms"] > cb["time_ms"]:
            why = (f"no threshold makes DACS as fast as checkerboard: its fastest point takes "
                   f"{eq_t['time_ms']:.2f} ms against {cb['time_ms']:.2f} ms (the five "
                   f"dependent levels' fixed cost); " + why).rstrip("; ")
        elif not eq_t["match_reached"]:
            why = (f"DACS is faster than checkerboard ({cb['time_ms']:.2f} ms) at every "
                   f"threshold of the sweep; the point nearest its time, "
                   f"{eq_t['threshold']:.3g}, takes {eq_t['time_ms']:.2f} ms; " + why
                   ).rstrip("; ")
        out.append(Claim(SOURCE, FIGURE, "DACS PSNR gain over checkerboard at equal time (dB)",
                         round(pub, 2), gain, cond, RELATION_TOL, baseline=0.0, reason=why))
    return out


def claims(rows: list[dict], conditions: str) -> list[Claim]:
    """The paper's claims against a ``dacs_vs_checkerboard`` run's rows, per scene and camera
    path; ``conditions`` describes the run (device, resolution, frames)."""
    by_case: dict = {}
    for r in table_rows(rows):
        by_case.setdefault((r["scene"], r["camera_path"]), {})[r["pipeline"]] = r
    out = []
    for (scene, path), case in sorted(by_case.items()):
        cond = (f"{scene}, {path}; {conditions}; ground truth deferred; time measured "
                f"(time_ms)")
        for label in PUBLISHED:
            if label in case:
                out += _absolute(label, case[label], cond)
        out += _relations(case, cond)
    return out
