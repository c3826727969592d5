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
