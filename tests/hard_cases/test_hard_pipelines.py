"""Every hard case through every registered pipeline (issue 10), at the catalogue's common
resolution: no NaN/Inf in the image, counts or metrics; display RMSE against the reference
within the case's bound; a bitwise-identical rerun. Pipelines are listed at run time, so a
pipeline that lands later is covered without an edit here.

All cases share one layout (jaxrender/scene/hard_cases.py), so each pipeline compiles once for
the whole file. The degenerate image sizes (1x16, 4096x1) are in test_hard_tiny_images.py so
that xdist runs them on the other worker.
"""

import pytest

from benchmarks.bench_hard_cases import evaluate, pipeline_names
from jaxrender.scene.hard_cases import CASES, RESOLUTION

COMMON = [n for n, c in CASES.items() if c.resolutions == (RESOLUTION,)]
CONSTANT_TOL = 1e-6  # colour range (max - min per channel) of a constant image


def check(row: dict, case) -> None:
    what = f"{row['case']} / {row['pipeline']} at {row['resolution']}"
    assert row["finite_image"], f"{what}: NaN/Inf in the image"
    assert row["finite_counts"], f"{what}: NaN/Inf in the counts"
    assert row["finite_metrics"], f"{what}: NaN/Inf in the metrics"
    assert row["deterministic"], f"{what}: a rerun is not bitwise identical"
    assert row["within_bound"], f"{what}: display RMSE {row['rmse']:.4g} > bound {case.bound}"
    if case.constant:
        assert row["image_range"] <= CONSTANT_TOL, f"{what}: not constant ({row['image_range']})"
    if case.empty:
        assert row["image_max"] == 0.0 and row["image_min"] == 0.0, f"{what}: not empty"
        assert row["shade_invocations"] == 0, f"{what}: shaded an empty view"


@pytest.mark.slow
@pytest.mark.parametrize("pipeline", pipeline_names())
@pytest.mark.parametrize("case", COMMON)
def test_hard_case_in_every_pipeline(case, pipeline):
    check(evaluate(case, pipeline, RESOLUTION), CASES[case])
