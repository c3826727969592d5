"""The command line: --help everywhere, user mistakes as one line with status 2, the commands
working end to end on fake scenes and pipelines."""

import json

import pytest

from jaxrender.cli import main

COMMANDS = [["study"], ["validate"], ["figures"], ["scenes"], ["pipelines"], ["render"],
            ["reference"], ["reference", "rebuild"], ["reference", "clear"],
            ["reference", "info"]]

STUDY = """
name = "cli"
resolution = "16x12"
scenes = ["tiny"]
figures = ["summary_table", "pareto_time"]
[timing]
warmup = 0
repeats = 1
[[paths]]
type = "fakepan"
frames = 2
[[pipelines]]
type = "flat"
sweep = { levels = [2, 8] }
"""


@pytest.fixture
def fake(monkeypatch, tmp_path):
    from tests.study import doubles

    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    doubles.install(monkeypatch)
    (tmp_path / "configs").mkdir()
    p = tmp_path / "cli.toml"
    p.write_text(STUDY)
    return p


@pytest.mark.parametrize("cmd", COMMANDS, ids=[" ".join(c) for c in COMMANDS])
def test_help(cmd, capsys):
    with pytest.raises(SystemExit) as e:
        main(cmd + ["--help"])
    assert e.value.code == 0
    assert "usage: jaxrender" in capsys.readouterr().out


def _one_line_error(capsys, *words):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err
    return err


def test_study_figures_and_resume(fake, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["study", str(fake), "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "PSNR" in text and "levels" in text
    assert (out / "results.csv").read_text().count("\n") == 1 + 2 * 2
    assert (out / "figures" / "summary_table.png").is_file()
    (out / "figures" / "summary_table.png").unlink()
    assert main(["figures", str(out), "--only", "summary_table"]) == 0
    assert (out / "figures" / "summary_table.png").is_file()
    assert main(["study", str(fake), "--out", str(out), "--no-progress", "--no-figures"]) == 0
    assert "2 of 2 sequences already stored" in capsys.readouterr().out
    assert main(["study", str(fake), "--out", str(out), "--no-progress", "--no-figures",
                 "--frames", "3", "--resolution", "12x12", "--force"]) == 0
    assert (out / "results.csv").read_text().count("\n") == 1 + 2 * 3


@pytest.mark.parametrize("argv, message", [
    (["--coordinator", "h:1"], "--coordinator needs --distributed"),
    (["--process-id", "1"], "--process-id needs --distributed"),
    (["--devices", "64"], "--devices 64: this process has 1 local device"),
])
def test_study_device_flags_are_checked(fake, tmp_path, capsys, argv, message):
    out = tmp_path / "out"
    assert main(["study", str(fake), "--out", str(out), "--no-progress", *argv]) == 2
    assert message in capsys.readouterr().err


def test_validate(fake, capsys):
    assert main(["validate", str(fake)]) == 0
    assert "ok (1 scene(s), 1 path(s), 2 variant(s), 4 frames" in capsys.readouterr().out


def test_listings(fake, capsys):
    assert main(["pipelines"]) == 0
    assert "flat" in capsys.readouterr().out
    assert main(["scenes"]) == 0
    assert "tiny2" in capsys.readouterr().out


def test_render(fake, tmp_path, capsys):
    png = tmp_path / "o" / "x.png"
    assert main(["render", "tiny", "--pipeline", "flat", "--set", "levels=4", "--set",
                 "mode=linear", "--resolution", "16x12", "-o", str(png), "--json",
                 "--repeats", "1"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["counts"]["covered_pixels"] == 16 * 12 and doc["params"]["levels"] == 4
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_reference_commands(fake, capsys):
    assert main(["reference", "rebuild", str(fake)]) == 0
    assert "rebuilt 2 reference frame(s)" in capsys.readouterr().out
    assert main(["reference", "info"]) == 0
    assert json.loads(capsys.readouterr().out)["entries"] == 2
    assert main(["reference", "clear"]) == 0
    assert "removed 2" in capsys.readouterr().out


@pytest.mark.parametrize("argv,words", [
    (["study", "nope.toml"], ["nope.toml: no such file"]),
    (["study", "cli.toml", "--resolution", "12"], ["--resolution"]),
    (["study", "cli.toml", "--frames", "0"], ["--frames", "positive integer"]),
    (["render", "tiny", "--pipeline", "warp", "-o", "x.png"], ["'warp' is not registered"]),
    (["render", "tiny", "--pipeline", "flat", "--set", "levels=many", "-o", "x.png"],
     ["--set: levels: expected an integer"]),
    (["render", "tiny", "--pipeline", "flat", "--set", "levels", "-o", "x.png"],
     ["expected key=value"]),
    (["figures", "."], ["not a study output directory"]),
    (["figures", ".", "--only", "nope"], ["not a study output directory"]),
    (["frobnicate"], ["invalid choice"]),
    (["render", "tiny", "-o", "x.png"], ["--pipeline"]),
])
def test_user_errors(fake, capsys, argv, words):
    try:
        code = main(argv)
    except SystemExit as e:  # argparse's own errors
        code = e.code
    assert code == 2
    _one_line_error(capsys, *words)
