"""A pipeline defined outside jaxrender, stateless (a step alone) or stateful (a counter in its
state), runs through ``jaxrender study`` with no change to the study code."""

import textwrap
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxrender import cli
from jaxrender.pipelines import registry
from jaxrender.study import store
from jaxrender.types import Frame


@dataclass(frozen=True)
class GainConfig(registry.RenderConfig):
    gain: float = 0.5


def _image(scene, camera, cfg, value):
    base = jnp.broadcast_to(scene.color, (cfg.height, cfg.width, 3))
    return base * value + 0.01 * camera.eye[0]


def gain_step(scene, static, state, camera, t, cfg):
    """test: stateless, a constant gain"""
    frame = Frame(_image(scene, camera, cfg, cfg.gain), {"shade_invocations": jnp.int32(7)}, {})
    return frame, state


def counter_init(scene, static, camera, cfg):
    return jnp.int32(0)


def counter_step(scene, static, count, camera, t, cfg):
    """test: stateful, counts the frames it has rendered"""
    frame = Frame(_image(scene, camera, cfg, cfg.gain) * 0 + count.astype(jnp.float32),
                  {"frames_seen": count, "frame_index": t}, {})
    return frame, count + 1


STUDY = """
name = "protocol"
resolution = "24x16"
frames = 3
warmup_frames = 1
save_frames = []
scenes = ["tiny"]
paths = [{ preset = "slowpan" }]

[timing]
warmup = 0
repeats = 1

[[pipelines]]
type = "gain_test"
sweep = { gain = [0.25, 0.75] }

[[pipelines]]
type = "counter_test"
"""


def test_new_pipelines_run_through_the_study_command(fake, monkeypatch, capsys):
    monkeypatch.setitem(registry.REGISTRY, "gain_test",
                        registry.Pipeline("gain_test", GainConfig, gain_step))
    monkeypatch.setitem(registry.REGISTRY, "counter_test",
                        registry.Pipeline("counter_test", GainConfig, counter_step,
                                          init=counter_init))
    f = fake / "studies" / "protocol.toml"
    f.parent.mkdir(exist_ok=True)
    f.write_text(textwrap.dedent(STUDY))
    out = fake / "run"
    assert cli.main(["study", str(f), "--out", str(out), "--no-progress", "--no-figures"]) == 0
    rows = store.read_rows(out / "results.jsonl")
    counter = sorted((r for r in rows if r["pipeline"] == "counter_test"),
                     key=lambda r: r["frame"])
    # one warm-up frame rendered before the three scored ones, the state carried through
    assert [r["frames_seen"] for r in counter] == [1, 2, 3]
    assert [r["frame_index"] for r in counter] == [1, 2, 3]
    assert all(r["warmup_frames"] == 1 and r["sequence_frames"] == 4 for r in counter)
    gains = {r["params"]["gain"]: r for r in rows if r["pipeline"] == "gain_test"
             and r["frame"] == 0}
    assert set(gains) == {0.25, 0.75} and gains[0.25]["shade_invocations"] == 7
    assert gains[0.25]["rmse"] != gains[0.75]["rmse"]
    assert np.isfinite([r["time_ms"] for r in rows]).all()
    assert all(r["time_ms_single"] > 0 for r in rows)


@dataclass(frozen=True)
class CapConfig(registry.RenderConfig):
    capacity: int = 100

    def overflow_hint(self) -> str:
        return f"raise capacity (now {self.capacity})"


def capped_step(scene, static, state, camera, t, cfg):
    """test: overflows when its capacity is below the pixel count"""
    need = cfg.width * cfg.height
    frame = Frame(_image(scene, camera, cfg, 1.0),
                  {"overflow": jnp.int32(max(0, need - cfg.capacity))}, {})
    return frame, state


def test_one_overflow_error_everywhere(fake, monkeypatch, capsys):
    import pytest

    from jaxrender.pipelines import PipelineOverflow
    from tests.study import doubles

    pipe = registry.Pipeline("capped_test", CapConfig, capped_step)
    monkeypatch.setitem(registry.REGISTRY, "capped_test", pipe)
    scene = doubles.FakeScene(jnp.ones(3), "tiny")
    cams = doubles.fake_pan(None, 2, 24, 16, step=0.0)
    small = CapConfig(width=24, height=16, capacity=10)
    with pytest.raises(PipelineOverflow, match=r"capped_test: .*raise capacity \(now 10\)"):
        pipe.render(scene, cams[0], small)
    with pytest.raises(PipelineOverflow, match=r"in frame\(s\) \[0, 1\]"):
        pipe.render_sequence(scene, cams, small)
    assert pipe.render(scene, cams[0], CapConfig(width=24, height=16, capacity=384)).image.shape \
        == (16, 24, 3)
    f = fake / "studies" / "capped.toml"
    f.parent.mkdir(exist_ok=True)
    f.write_text(textwrap.dedent(STUDY).split("[[pipelines]]")[0]
                 + '[[pipelines]]\ntype = "capped_test"\nparams = { capacity = 10 }\n')
    assert cli.main(["study", str(f), "--out", str(fake / "capped"), "--no-progress",
                     "--no-figures"]) == 3
    err = capsys.readouterr().err
    assert "scene 'tiny', path 'slowpan', pipeline 'capped_test'" in err and "now 10" in err
    assert store.read_rows(fake / "capped" / "results.jsonl") == []  # nothing half-written


def test_registered_pipelines_pickle_by_reference():
    """The study's compile workers receive pipelines pickled: every built-in must survive it."""
    import pickle

    for pipe in registry.list_pipelines():
        assert pickle.loads(pickle.dumps(pipe)) == pipe, pipe.name
