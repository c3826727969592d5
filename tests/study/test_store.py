"""The result store: atomic appends, partial last lines, the CSV export; the timing helpers."""

import csv
import json

import jax.numpy as jnp

from jaxrender import timing
from jaxrender.study import store


def _rows(seq, n):
    return [{"seq": seq, "frame": t, "scene": "s", "camera_path": "p", "pipeline": "x",
             "params": {"a": 1}, "psnr": float("inf"), "extra_count": t} for t in range(n)]


def test_append_and_complete(tmp_path):
    st = store.ResultStore(tmp_path / "r.jsonl")
    st.append(_rows("a", 3))
    st.append(_rows("b", 2))
    assert st.complete("a", 3) and st.complete("b", 2) and not st.complete("b", 3)
    again = store.ResultStore(tmp_path / "r.jsonl")
    assert len(again.rows) == 5 and again.complete("a", 3)
    assert again.rows[0]["psnr"] == float("inf")


def test_partial_line_ignored_then_cut(tmp_path):
    p = tmp_path / "r.jsonl"
    st = store.ResultStore(p)
    st.append(_rows("a", 2))
    with open(p, "ab") as f:
        f.write(b'{"seq": "b", "fra')
    assert len(store.read_rows(p)) == 2  # reading never counts the half row
    st = store.ResultStore(p)
    assert st.dropped_bytes == len(b'{"seq": "b", "fra') and p.read_bytes().endswith(b"\n")
    st.append(_rows("b", 1))
    assert [r["seq"] for r in store.read_rows(p)] == ["a", "a", "b"]


def test_force_starts_empty(tmp_path):
    p = tmp_path / "r.jsonl"
    store.ResultStore(p).append(_rows("a", 2))
    assert store.ResultStore(p, force=True).rows == []


def test_latest_rows_last_wins(tmp_path):
    rows = _rows("a", 2) + [dict(_rows("a", 1)[0], psnr=30.0)] + _rows("z", 1)
    latest = store.latest_rows(rows, {"a"})
    assert len(latest) == 2 and {r["psnr"] for r in latest} == {30.0, float("inf")}


def test_csv_columns(tmp_path):
    p = tmp_path / "r.csv"
    store.export_csv(_rows("a", 2), p)
    with open(p, newline="") as f:
        rd = csv.DictReader(f)
        rows = list(rd)
    assert rd.fieldnames[: len(store.CSV_COLUMNS)] == list(store.CSV_COLUMNS)
    assert rd.fieldnames[-1] == "extra_count"
    assert json.loads(rows[0]["params"]) == {"a": 1} and rows[0]["psnr"] == "inf"


def test_timing_median_and_compile():
    from jaxrender.pipelines import registry
    from jaxrender.types import Frame

    def frame(scene, camera, cfg):
        return Frame(scene * cfg.width + camera, {}, {})

    pipe = registry.Pipeline("affine", registry.RenderConfig, registry.FrameStep(frame))
    comp = timing.compile_program(pipe, jnp.ones(4), jnp.float32(2.0),
                                  registry.RenderConfig(width=3, height=1))
    assert comp.compile_ms > 0
    out, med, samples = timing.time_call(comp.call, jnp.ones(4), jnp.float32(1.0), repeats=3,
                                         warmup=1)
    assert float(out.image[0]) == 4.0 and len(samples) == 3 and min(samples) <= med <= max(samples)
    info = timing.environment()
    assert info["device"].startswith("cpu") and info["jax_version"]
