"""The one-command report: every source's claims collected from its study's run, written as
Markdown and CSV, with the DACS source and a fake one (as the other sources plug in)."""

from __future__ import annotations

import csv
import json
import sys
import types

import pytest

from jaxrender import cli
from jaxrender.seeds import claim, dacs, report
from jaxrender.study.schema import load_study
from jaxrender.study.specs import to_toml
from tests.seeds.test_dacs_seed import _run

FAKE_STUDY = """
name = "fake_seed"
resolution = "32x18"
scenes = ["spheres"]
[[pipelines]]
type = "deferred"
"""


def _fake_source(study_file):
    def claims(rows, conditions):
        n = sum(r["pipeline"] == "deferred" for r in rows)
        return [claim.Claim("Fake 2020", "Fig. 1", "deferred frames", 2.0, float(n), conditions,
                            0.0),
                claim.Claim("Fake 2020", "Fig. 2", "waves ratio", 0.4, 0.5, conditions, 0.1,
                            baseline=1.0, reason="coarser tiles")]
    return types.SimpleNamespace(SOURCE="Fake 2020", STUDY=str(study_file), claims=claims)


def _store_run(runs, study, rows):
    run_dir = runs / study.name
    run_dir.mkdir(parents=True)
    (run_dir / "study.toml").write_text(to_toml(study))
    (run_dir / "environment.json").write_text(json.dumps(
        {"device": "TestDevice", "date": "2026-12-02 03:00:00"}))
    (run_dir / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return run_dir


@pytest.fixture
def runs(tmp_path):
    (tmp_path / "fake.toml").write_text(FAKE_STUDY)
    fake = _fake_source(tmp_path / "fake.toml")
    runs = tmp_path / "runs"
    _store_run(runs, load_study(dacs.STUDY), _run(eq_q_ms=1.0, eq_t_psnr=40.0))
    _store_run(runs, load_study(fake.STUDY), [
        {"seq": "a", "frame": t, "scene": "spheres", "camera_path": "static",
         "pipeline": "deferred", "params": {}} for t in range(2)])
    return runs, fake


def test_report_collects_every_source_and_writes_markdown_and_csv(runs, tmp_path):
    runs, fake = runs
    claims = report.collect(runs, sources=[dacs, fake], read_only=True, log=lambda *_: None)
    fake_claims = [c for c in claims if c.source == "Fake 2020"]
    assert [c.verdict for c in fake_claims] == [claim.REPRODUCED, claim.DIRECTION]
    assert fake_claims[0].conditions == "32x18, 1 frames, TestDevice, 2026-12-02"
    assert len(claims) == len(dacs.claims(_run(eq_q_ms=1.0, eq_t_psnr=40.0), "x")) + 2
    md, csv_path = report.write_report(claims, tmp_path / "out")
    with csv_path.open() as f:
        table = list(csv.DictReader(f))
    assert list(table[0]) == list(report.COLUMNS)
    assert len(table) == len(claims)
    last = table[-1]
    assert (last["quantity"], last["published"], last["ours"], last["verdict"],
            last["reason"]) == ("waves ratio", "0.4", "0.5", claim.DIRECTION, "coarser tiles")
    text = md.read_text()
    assert f"{len(claims)} claims:" in text
    assert "| Fake 2020 | Fig. 1 | deferred frames | 2 | 2 |" in text
    assert "reproduced within 0%" in text
    # The DACS source's own table went beside its run.
    assert "dacs_equal_quality" in (runs / dacs.STUDY / "dacs_table.md").read_text()


def test_report_command_reads_the_runs_of_the_listed_sources(runs, tmp_path, monkeypatch,
                                                             capsys):
    runs, fake = runs
    monkeypatch.setitem(sys.modules, "tests_fake_seed", fake)
    monkeypatch.setattr(report, "SOURCES", ("jaxrender.seeds.dacs", "tests_fake_seed"))
    assert cli.main(["report", "--runs", str(runs), "--read", "--out",
                     str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "| Fake 2020 | Fig. 2 | waves ratio |" in out
    assert "| DACS (Mallett and Yuksel 2018) | Table 1" in out
    assert (tmp_path / "out" / "report.csv").is_file()
    assert (tmp_path / "out" / "dacs_table.md").is_file(), "the source's table beside the report"


def test_report_read_without_a_run_says_what_to_do(tmp_path, capsys):
    assert cli.main(["report", "--runs", str(tmp_path / "none"), "--read"]) == 2
    assert "no results.jsonl; run the report without --read" in capsys.readouterr().err


def test_a_study_run_writes_the_table_of_the_source_it_measures(tmp_path):
    rows = _run(eq_q_ms=1.0, eq_t_psnr=40.0)
    assert report.tables_for_study("quickstart", rows, tmp_path, log=lambda *_: None) == []
    (md,) = report.tables_for_study(dacs.STUDY, rows, tmp_path, log=lambda *_: None)
    assert md == tmp_path / "dacs_table.md"
    with (tmp_path / "dacs_table.csv").open() as f:
        table = list(csv.DictReader(f))
    assert [r["pipeline"] for r in table] == ["checkerboard", "dacs_equal_quality",
                                              "dacs_equal_time"]
