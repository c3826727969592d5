"""The Decima claims from hand-made study rows: ratios per scene, verdicts, missing rows."""

import pytest

from jaxrender.seeds import decima
from jaxrender.seeds.claim import DIRECTION, NOT_MEASURED, NOT_REPRODUCED, REPRODUCED
from jaxrender.study.schema import load_study, study_file


def _row(scene, pipeline, waves, vertices, frame=0):
    return {"scene": scene, "pipeline": pipeline, "frame": frame, "waves": waves,
            "vertex_invocations": vertices}


def _rows():
    return [
        # foliage: two frames, means 9000/25000 waves = 0.36, vertices 1500/1000 = 1.5
        _row("foliage", "forward_prepass", 24000, 1000), _row("foliage", "forward_prepass",
                                                              26000, 1000, 1),
        _row("foliage", "visbuffer_loose", 8000, 1500), _row("foliage", "visbuffer_loose",
                                                             10000, 1500, 1),
        _row("foliage", "visbuffer_tiles", 99999, 99999),  # not the claim's variant
        # grass: waves 6000/10000 = 0.6 (direction only), vertices 550/1000 = 0.55
        _row("grass", "forward_prepass", 10000, 1000), _row("grass", "visbuffer_loose", 6000,
                                                            550),
    ]


def test_ratios_and_verdicts_from_rows():
    got = {(c.quantity, c.conditions.split("scene ")[1][:9]): c
           for c in decima.claims(_rows(), "1920x1080, cpu")}
    by = {c.quantity: c for c in got.values()}
    forest_waves = by["pixel shading waves, visbuffer / depth-equal pass (forest)"]
    assert forest_waves.published == 0.40 and forest_waves.ours == pytest.approx(0.36)
    assert forest_waves.verdict == REPRODUCED  # within 25% of 0.40
    assert forest_waves.tolerance == 0.25 and forest_waves.baseline == 1.0
    assert "'foliage'" in forest_waves.conditions and "1920x1080, cpu" in forest_waves.conditions
    grass_waves = by["pixel shading waves, visbuffer / depth-equal pass (tall grass)"]
    assert grass_waves.ours == pytest.approx(0.6) and grass_waves.verdict == DIRECTION
    assert grass_waves.reason
    forest_vertices = by["vertex work, visbuffer / forward + pre-pass (forest)"]
    assert forest_vertices.ours == pytest.approx(1.5)
    assert forest_vertices.verdict == NOT_REPRODUCED and "vertices" in forest_vertices.reason
    grass_vertices = by["vertex work, visbuffer / forward + pre-pass (tall grass)"]
    assert grass_vertices.ours == pytest.approx(0.55) and grass_vertices.verdict == REPRODUCED
    assert grass_vertices.reason == ""
    assert len(got) == 4


def test_missing_rows_are_not_measured_with_the_reason():
    rows = [r for r in _rows() if not (r["scene"] == "grass"
                                       and r["pipeline"] == "visbuffer_loose")]
    claims = decima.claims(rows, "c")
    grass = [c for c in claims if "tall grass" in c.quantity]
    assert [c.verdict for c in grass] == [NOT_MEASURED, NOT_MEASURED]
    assert all("visbuffer_loose" in c.reason for c in grass)


def test_the_study_exists_and_has_the_claims_variants():
    study = load_study(study_file(decima.STUDY))
    labels = {v.label for v in study.variants}
    assert {decima.VISBUFFER, decima.FORWARD} <= labels
    assert {s.label for s in study.scenes} == {"foliage", "grass"}
    assert study.resolution == (1920, 1080)
