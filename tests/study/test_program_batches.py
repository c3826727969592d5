"""A study's sequences in batches of programs: the split itself, and a batched run giving the
rows of an unbatched one."""

import json
import math

from jaxrender import memory_maps
from jaxrender.study import program_batches
from jaxrender.study.runner import run_study
from jaxrender.study.schema import load_study


def test_batches_keep_sharing_items_together_and_the_bound():
    # item -> the programs it runs; b and d share program 2, so they stay in one batch
    runs = {"a": {1}, "b": {2, 3}, "c": {4}, "d": {2, 5}, "e": {6}}
    todo = list(runs)
    out = program_batches.batches(todo, runs.__getitem__, 3)
    assert sorted(x for b in out for x in b) == todo, "every item exactly once"
    for batch in out:
        held = set().union(*(runs[x] for x in batch))
        assert len(held) <= 3, (batch, held)
        assert batch == sorted(batch), f"{batch}: the study's order is kept inside a batch"
    together = [b for b in out if "b" in b]
    assert "d" in together[0], out
    assert program_batches.batches(todo, runs.__getitem__, None) == [todo]
    assert program_batches.batches([], runs.__getitem__, 3) == []


def test_a_group_larger_than_the_bound_is_a_batch_of_its_own():
    runs = {"a": {1, 2, 3}, "b": {4}}
    assert program_batches.batches(["a", "b"], runs.__getitem__, 2) == [["a"], ["b"]]


def test_programs_at_once_on_this_backend(monkeypatch, tmp_path):
    limit = tmp_path / "max_map_count"
    limit.write_text("65530\n")
    monkeypatch.setattr(memory_maps, "MAP_COUNT_FILE", limit)
    assert program_batches.programs_at_once() == 65530 // 2 // program_batches.REGIONS_PER_PROGRAM
    monkeypatch.setattr(memory_maps, "MAP_COUNT_FILE", tmp_path / "missing")
    assert program_batches.programs_at_once() is None


def _same(x, y) -> bool:
    return x == y or (isinstance(x, float) and isinstance(y, float) and math.isnan(x)
                      and math.isnan(y))  # the first frame's temporal error is NaN


def _rows(out):
    # What a run measures of itself (times, compile method) differs; what it scored may not.
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    return sorted(({k: v for k, v in r.items()
                    if not k.startswith(("time", "compile", "sequence_ms"))}
                   for r in rows), key=lambda r: (r["seq"], r["frame"]))


def test_a_batched_run_gives_the_rows_of_one_batch(tiny_study, tmp_path, monkeypatch):
    study = load_study(tiny_study)
    monkeypatch.setattr(program_batches, "programs_at_once", lambda: None)
    whole = run_study(study, tmp_path / "whole", progress=False, log=lambda s: None)
    logs = []
    monkeypatch.setattr(program_batches, "programs_at_once", lambda: 3)
    batched = run_study(study, tmp_path / "batched", progress=False, log=logs.append)
    # 2 scenes x 3 variants, each an instrumented and an images-only sequence program and a
    # single-frame program: 6 batches of 3
    assert any("6 batches" in line for line in logs), logs
    assert sum("compiled or loaded 3 program(s)" in line for line in logs) == 6, logs
    assert batched.computed == whole.computed == 6
    a, b = _rows(tmp_path / "whole"), _rows(tmp_path / "batched")
    assert len(a) == len(b) == 18
    differ = {k for x, y in zip(a, b) for k in x if not _same(x[k], y.get(k))}
    assert not differ, f"a batched run scores the same frames as one batch; differ: {differ}"

