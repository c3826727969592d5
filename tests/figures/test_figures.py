"""Figure functions are pure: the same table gives the same PNG and PDF bytes, and the table
is not modified."""

import copy

import numpy as np
import pytest

from jaxrender import figures
from jaxrender.figures import data


def _img(seed, h=12, w=16):
    return np.random.default_rng(seed).random((h, w, 3)).astype(np.float32)


TABLES = {
    "image_grid": (figures.fig_image_grid, {
        "title": "tiny", "device": "cpu", "reference": _img(0), "crop": (2, 3, 6, 6),
        "error_max": 0.5, "entries": [
            {"label": "a", "image": _img(1), "error": _img(2)[..., 0], "caption": "PSNR 20"},
            {"label": "b", "image": _img(3), "error": _img(4)[..., 0]}]}),
    "pareto": (figures.fig_pareto, {
        "title": "t", "xlabel": "time", "ylabel": "PSNR", "logx": True, "device": "cpu",
        "series": [{"label": "a", "x": [1.0, 2.0, 4.0], "y": [20.0, 25.0, 27.0]},
                   {"label": "b", "x": [3.0], "y": [22.0]}],
        "front": [(1.0, 20.0), (2.0, 25.0), (4.0, 27.0)]}),
    "temporal": (figures.fig_temporal, {
        "title": "t", "series": [{"label": "a", "frames": [0, 1, 2],
                                  "temporal": [float("nan"), 0.1, 0.2],
                                  "psnr": [30.0, 31.0, 29.0]}]}),
    "dacs": (figures.fig_dacs_decisions, {
        "title": "t", "entries": [{"label": "dacs", "image": _img(5),
                                   "level": (np.arange(192).reshape(12, 16) % 5),
                                   "shaded": np.eye(12, 16, dtype=bool)}]}),
    "object_space": (figures.fig_object_space_marking, {
        "title": "t", "entries": [{"label": "os", "image": _img(6),
                                   "chunk_state": np.array([[0, 1], [2, 1]]),
                                   "mip_level": _img(7)[..., 0]}]}),
    "tads": (figures.fig_tads_samples, {
        "title": "t", "entries": [{"label": "tads", "image": _img(8),
                                   "sample_class": np.arange(192).reshape(12, 16) % 6 - 1,
                                   "duplicates": np.eye(12, 16, dtype=np.int32)}]}),
    "waves": (figures.fig_visbuffer_waves, {
        "title": "t", "labels": ["vb", "vb vrs=2x2"], "waves": [120.0, 40.0],
        "utilization": [0.9, 0.6]}),
    "time_work": (figures.fig_time_work, {
        "title": "t", "xlabel": "work", "ylabel": "ms", "baseline": "deferred", "log": True,
        "device": "cpu", "series": [
            {"label": "deferred", "work": [1.0, 5.0, 65.0], "time": [2.0, 2.4, 7.1],
             "line_work": [1.0, 65.0], "line_time": [2.0, 7.1], "linear": True},
            {"label": "checkerboard", "work": [0.5, 2.5, 32.5], "time": [3.0, 3.2, 5.6],
             "line_work": [0.5, 32.5], "line_time": [3.0, 5.6], "linear": False}],
        "crossings": [{"label": "checkerboard", "cost": 25.7, "work": 13.4, "time": 4.0}]}),
    "summary": (figures.fig_summary_table, {
        "title": "t", "columns": ["pipeline", "PSNR"], "rows": [["a", 30.123], ["b", float("nan")]]}),
}


@pytest.mark.parametrize("name", sorted(TABLES))
def test_pure_and_deterministic(name, tmp_path):
    fn, table = TABLES[name]
    before = copy.deepcopy(table)
    a = figures.save_figure(fn(table), tmp_path / "a" / name)
    b = figures.save_figure(fn(table), tmp_path / "b" / name)
    for pa, pb in zip(a, b):
        assert pa.stat().st_size > 0
        assert pa.read_bytes() == pb.read_bytes(), pa.suffix
    for k in table:  # the input is not modified
        if isinstance(table[k], np.ndarray):
            np.testing.assert_array_equal(table[k], before[k])
    assert repr(table) == repr(before)


def test_pdf_has_no_dates(tmp_path):
    fn, table = TABLES["pareto"]
    _, pdf = figures.save_figure(fn(table), tmp_path / "p")
    assert b"CreationDate" not in pdf.read_bytes()


def test_pareto_front():
    pts = [(1.0, 20.0), (2.0, 19.0), (3.0, 25.0), (0.5, 10.0), (4.0, float("nan"))]
    assert data.pareto_front(pts) == [(0.5, 10.0), (1.0, 20.0), (3.0, 25.0)]


def test_variant_name():
    assert data.variant_name("dacs", {}) == "dacs"
    assert data.variant_name("dacs", '{"threshold": 0.1}') == "dacs threshold=0.1"


def test_time_label_says_what_was_timed():
    base = "time per frame (ms, median"
    assert data.time_label([{"timed_outputs": "images"}] * 2) == base + ", images only)"
    # rows stored before timed_outputs existed were timed with their counts
    assert data.time_label([{}, {"timed_outputs": "all"}]) == base + ", counts included)"
    assert data.time_label([{"timed_outputs": "images"}, {}]) == base + ")", "mixed: no claim"
