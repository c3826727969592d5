"""Loose tiling (Decima): 128x128 tiles, complete waves of one batch group, command bytes."""

import jax.numpy as jnp
import numpy as np
from fdv_scenes import H, W, foliage_scene

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines.loose_tiles import (PIXEL_COMMAND_BYTES, WAVE_COMMAND_BYTES,
                                             command_counts, loose_order)
from jaxrender.pipelines.micro_batch import micro_batches, unpack

T = 128


def _tile_groups() -> np.ndarray:
    """One 128x128 tile, three batch groups, worked by hand: group 0 the left 40 columns (5120
    pixels: 80 full waves of 64), group 1 a 10x10 block (100 pixels: 2 waves, 28 lanes
    unfilled), group 2 a single pixel (1 wave, 63 unfilled); -1 where nothing is shaded."""
    g = np.full((T, T), -1, np.int32)
    g[:, :40] = 0
    g[50:60, 70:80] = 1
    g[127, 127] = 2
    return g


def _loose(groups: np.ndarray, wave_size: int = 64):
    h, w = groups.shape
    flat = jnp.asarray(groups.reshape(-1))
    pix = jnp.arange(w * h, dtype=jnp.int32)
    live = flat >= 0
    order, starts, live_s = loose_order(live, jnp.maximum(flat, 0), pix % w, pix // w, w, h, 3)
    inv = jnp.sum(live, dtype=jnp.int32)
    return order, starts, live_s, command_counts(starts, live_s, wave_size, inv, "loose")


def test_a_hand_worked_tile_gives_exact_waves_lanes_and_command_bytes():
    groups = _tile_groups()
    order, starts, live_s, c = _loose(groups)
    assert int(c["waves"]) == 80 + 2 + 1
    assert int(c["unfilled_lanes"]) == 0 + 28 + 63
    assert int(c["pixel_command_bytes"]) == (5120 + 100 + 1) * PIXEL_COMMAND_BYTES == 10442
    assert int(c["wave_command_bytes"]) == 83 * WAVE_COMMAND_BYTES == 332
    np.testing.assert_allclose(float(c["lane_utilization"]), 5221 / (83 * 64), rtol=1e-6)
    # The sorted list: each group's pixels together, in Morton order inside the tile; every
    # wave of 64 consecutive items of a run holds one group only.
    n = 5221
    got = groups.reshape(-1)[np.asarray(order)[:n]]
    np.testing.assert_array_equal(got, np.repeat([0, 1, 2], [5120, 100, 1]))
    assert int(np.asarray(starts).sum()) == 3 and int(np.asarray(live_s).sum()) == n
    block = np.asarray(order)[5120:5220]
    np.testing.assert_array_equal(block, block[np.argsort(_morton(block % T, block // T))],
                                  err_msg="Morton order inside a tile")
    # A full wave of group 0 is an 8x8 block of pixels.
    first = np.asarray(order)[:64]
    assert np.ptp(first % T) == 7 and np.ptp(first // T) == 7


def _morton(x, y):
    """NumPy: bits of x and y interleaved (x lowest)."""
    return sum(((x >> b) & 1) << (2 * b) | ((y >> b) & 1) << (2 * b + 1) for b in range(7))


def test_tiles_are_separate_runs_and_wave_size_32():
    # Two tiles side by side, the same layout in each, waves of 32: each tile pays its own
    # partly filled waves (160 + 4 + 1 per tile).
    groups = np.concatenate([_tile_groups(), _tile_groups()], axis=1)
    *_, c = _loose(groups, wave_size=32)
    assert int(c["waves"]) == 2 * (160 + 4 + 1)
    assert int(c["unfilled_lanes"]) == 2 * (0 + 28 + 31)


def _waves_oracle(mat: np.ndarray, wave_size: int, tile: int) -> int:
    """NumPy: waves of (tile, material) groups."""
    h, w = mat.shape
    y, x = np.nonzero(mat >= 0)
    key = (y // tile) * ((w + tile - 1) // tile) + x // tile
    _, n = np.unique(np.stack([key, mat[y, x]]), axis=1, return_counts=True)
    return int(np.sum(-(-n // wave_size)))


def test_visbuffer_counts_follow_the_tiling_on_foliage():
    scene = foliage_scene()
    vb = get_pipeline("visbuffer")
    # Waves of 32, the default: the programs of test_visbuffer.py serve here too.
    frames = {t: vb.render(scene, scene.camera, make_config(
        "visbuffer", width=W, height=H, tiling=t)) for t in ("loose", "tiles")}
    ids = np.asarray(frames["loose"].aux["ids"])
    for t, f in frames.items():
        np.testing.assert_array_equal(np.asarray(f.image), np.asarray(frames["loose"].image),
                                      err_msg=f"tiling {t} changed the image")
    mb = micro_batches(scene.tri_object, scene.tri_material)
    tri, _ = unpack(mb, jnp.asarray(ids), 0)
    tri = np.asarray(tri)
    mat = np.where(tri >= 0, np.asarray(scene.tri_material)[np.maximum(tri, 0)], -1)
    inv = int((mat >= 0).sum())
    for t, tile in (("loose", 128), ("tiles", 8)):
        c = frames[t].counts
        assert int(c["shade_invocations"]) == inv
        assert int(c["waves"]) == _waves_oracle(mat, 32, tile), t
        assert int(c["unfilled_lanes"]) == int(c["waves"]) * 32 - inv, t
    assert int(frames["loose"].counts["pixel_command_bytes"]) == 2 * inv
    assert int(frames["tiles"].counts["pixel_command_bytes"]) == 0
