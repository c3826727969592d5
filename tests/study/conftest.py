"""Fixtures for the study tests: fake scenes, pipelines and metrics; a private cache."""

import textwrap

import pytest


@pytest.fixture
def fake(monkeypatch, tmp_path):
    from tests.study import doubles

    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "cache"))
    doubles.install(monkeypatch)
    (tmp_path / "configs" / "paths").mkdir(parents=True)
    (tmp_path / "configs" / "pipelines").mkdir(parents=True)
    (tmp_path / "configs" / "scenes").mkdir(parents=True)
    (tmp_path / "configs" / "paths" / "slowpan.toml").write_text(
        'type = "fakepan"\nframes = 3\n[params]\nstep = 0.02\n')
    (tmp_path / "configs" / "pipelines" / "coarse.toml").write_text(
        'type = "flat"\n[params]\nlevels = 2\n')
    return tmp_path


TINY = """
name = "tiny"
resolution = "24x16"
frames = 3
save_frames = [0]
scenes = ["tiny", "tiny2"]

[timing]
warmup = 0
repeats = 1

[[paths]]
preset = "slowpan"

[[pipelines]]
type = "flat"
sweep = { levels = [4, 16] }

[[pipelines]]
preset = "coarse"
params = { noise = 0.01 }
"""


@pytest.fixture
def tiny_study(fake):
    p = fake / "studies" / "tiny.toml"
    p.parent.mkdir()
    p.write_text(textwrap.dedent(TINY))
    return p
