"""The degenerate image sizes of the catalogue (1 pixel wide, 4096 x 1) in every pipeline;
the same checks as test_hard_pipelines.py."""

import pytest

from benchmarks.bench_hard_cases import evaluate, pipeline_names
from jaxrender.scene.hard_cases import CASES, RESOLUTION
from tests.hard_cases.test_hard_pipelines import check

TINY = [(n, r) for n, c in CASES.items() for r in c.resolutions if r != RESOLUTION]


@pytest.mark.slow
@pytest.mark.parametrize("pipeline", pipeline_names())
@pytest.mark.parametrize("case,resolution", TINY, ids=[f"{n}-{w}x{h}" for n, (w, h) in TINY])
def test_tiny_image_in_every_pipeline(case, resolution, pipeline):
    check(evaluate(case, pipeline, resolution), CASES[case])
