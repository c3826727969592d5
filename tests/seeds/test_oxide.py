"""Oxide's claims from hand-made study rows: which rows each claim reads, its value, verdict
and reason."""

from __future__ import annotations

import pytest

from jaxrender.seeds import oxide
from jaxrender.seeds.claim import NOT_MEASURED, NOT_REPRODUCED, REPRODUCED


def row(store, feedback=False, scene="room", **counts):
    params = {"store_per_pixel": store, **({"bias_feedback": True} if feedback else {})}
    base = {"shadels_per_pixel": 2.6, "mip_bias": 0.0, "mip_chain_memory": 1.3125,
            "id_map_bits_per_shadel": 32.0, "chunk_metadata_bits_per_shadel": 2.5,
            "chunks_unshaded": 0, "chunks_requested": 40}
    return {"pipeline_type": "object_space", "scene": scene, "params": params,
            **base, **counts}


ROWS = [
    row(8.0, shadels_per_pixel=2.2), row(8.0, scene="terrain", shadels_per_pixel=2.6),
    row(1.0, shadels_per_pixel=0.9, mip_bias=1.5),  # a small store: not the rule of thumb
    row(8.0, feedback=True, chunks_unshaded=0), row(8.0, feedback=True, chunks_unshaded=0),
    row(1.0, feedback=True, chunks_unshaded=30),  # over budget: not the widest store
    {"pipeline_type": "deferred", "scene": "room", "params": {}, "shadels_per_pixel": 99.0},
]


def by_quantity(claims):
    return {c.quantity.split(",")[0].split(" (")[0]: c for c in claims}


def test_claims_read_the_widest_store_of_each_mode():
    cs = by_quantity(oxide.claims(ROWS, "48x27, CPU"))
    spp = cs["shadels per pixel"]
    assert spp.ours == pytest.approx(2.4, abs=1e-12), "mean of the two 8/px in-frame rows"
    assert spp.published == 2.5 and spp.verdict == REPRODUCED  # 2.4 within 2.5 +- 0.5
    assert "room, terrain" in spp.conditions and "8 shadels/pixel" in spp.conditions
    chain = cs["full MIP chain memory over level 0"]
    assert chain.ours == pytest.approx(1.3125) and chain.verdict == REPRODUCED
    bits = cs["ID map + per-chunk metadata"]
    assert bits.ours == pytest.approx(34.5) and bits.verdict == NOT_REPRODUCED
    assert "32.00" in bits.reason and "2.50" in bits.reason
    under = cs["fraction of requested chunks left unshaded"]
    assert under.ours == 0.0 and under.verdict == REPRODUCED, "the 1/px rows are not read"


def test_undershading_and_a_biased_widest_store_are_reported_with_reasons():
    rows = [row(2.0, shadels_per_pixel=1.9, mip_bias=0.5),
            row(2.0, feedback=True, chunks_unshaded=4, chunks_requested=40)]
    cs = by_quantity(oxide.claims(rows, "c"))
    assert "MIP bias" in cs["shadels per pixel"].reason
    under = cs["fraction of requested chunks left unshaded"]
    assert under.ours == pytest.approx(0.1) and under.verdict == NOT_REPRODUCED
    assert "4.0 of 40.0" in under.reason


def test_without_object_space_rows_nothing_is_measured():
    cs = oxide.claims([{"pipeline_type": "forward", "params": {}}], "c")
    assert len(cs) == 4 and all(c.verdict == NOT_MEASURED for c in cs)
    assert all(oxide.STUDY in c.reason for c in cs), [c.reason for c in cs]
    assert oxide.STUDY == "oxide_store_pressure" and all(c.source == oxide.SOURCE for c in cs)


def test_a_square_chain_of_four_thirds_reproduces_the_published_range():
    # 1.25-1.33 as published: 4/3 (a square power-of-two chain) is the 1.33, rounded.
    cs = by_quantity(oxide.claims([row(8.0, mip_chain_memory=4.0 / 3.0)], "c"))
    assert cs["full MIP chain memory over level 0"].verdict == REPRODUCED
    cs = by_quantity(oxide.claims([row(8.0, mip_chain_memory=1.5)], "c"))
    assert cs["full MIP chain memory over level 0"].verdict != REPRODUCED
