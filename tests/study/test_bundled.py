"""The bundled study files and presets are valid as far as the landed pieces allow."""

import tomllib
from pathlib import Path

import pytest

from jaxrender.errors import StudyError
from jaxrender.study.schema import load_study

ROOT = Path(__file__).resolve().parents[2]
STUDIES = sorted((ROOT / "studies").glob("*.toml"))
PIPELINE_TYPES = {"forward", "deferred", "visbuffer", "checkerboard", "dacs", "object_space",
                  "tads"}


def test_all_bundled_studies_exist():
    names = {p.stem for p in STUDIES}
    assert {"quickstart", "pipelines_overview", "dacs_vs_checkerboard", "temporal_stability",
            "hard_cases", "performance"} <= names


@pytest.mark.parametrize("path", STUDIES, ids=[p.stem for p in STUDIES])
def test_bundled_study_validates(path, monkeypatch):
    monkeypatch.chdir(ROOT)
    try:
        load_study(path.relative_to(ROOT))
    except StudyError as e:  # only a pipeline that has not landed yet may stop it
        if "is not registered" in str(e) or (path.stem == "quickstart"
                                             and "missing required key 'pipelines'" in str(e)):
            pytest.skip(str(e))
        raise


def test_quickstart_pending_blocks_parse():
    text = (ROOT / "studies" / "quickstart.toml").read_text().replace("#pending ", "")
    doc = tomllib.loads(text)
    assert {p["type"] for p in doc["pipelines"]} <= PIPELINE_TYPES


@pytest.mark.parametrize("path", sorted((ROOT / "configs" / "pipelines").glob("*.toml")) +
                         sorted((ROOT / "configs" / "paths").glob("*.toml")),
                         ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_presets_parse(path):
    doc = tomllib.loads(path.read_text())
    assert "type" in doc
