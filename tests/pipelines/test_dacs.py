"""DACS: the level pattern, the two threshold limits against deferred, exact reconstruction of
a ramp and a step under an image-lookup shader, borders and odd sizes, the warp simulation."""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.pipelines import dacs as dacs_mod
from jaxrender.pipelines import deferred, make_config, program
from jaxrender.pipelines.dacs_levels import level_map, level_pixels, n_levels, parent_pairs
from jaxrender.pipelines.dacs_warp import simulate
from tests.pipelines.dacs_scenes import H, W, flat_scene, shapes_scene

# Deferred and DACS shade the same points with the same code in two compiled programs; XLA may
# fuse the float math differently, which leaves at most a few ulps (seen: 1 ulp).
_ULP_RTOL = 1e-6
SIZES = [(1, 1), (1, 7), (7, 1), (5, 3), (33, 21), (34, 22), (32, 24)]


@pytest.mark.parametrize("spacing", [4, 8])
@pytest.mark.parametrize("w,h", SIZES)
def test_levels_visit_every_pixel_once(w, h, spacing):
    per = level_pixels(h, w, spacing)
    assert len(per) == n_levels(spacing)
    allpix = np.sort(np.concatenate(per))
    np.testing.assert_array_equal(allpix, np.arange(w * h))
    lv = level_map(h, w, spacing)
    for k in range(1, len(per)):  # parents lie on earlier levels; one is always inside
        ys, xs = per[k] // w, per[k] % w
        inside_any = np.zeros(len(ys), bool)
        for pair in parent_pairs(k, spacing):
            for dy, dx in pair:
                py, px = ys + dy, xs + dx
                ok = (py >= 0) & (py < h) & (px >= 0) & (px < w)
                assert np.all(lv[py[ok], px[ok]] < k)
                inside_any |= ok
        assert inside_any.all()


def test_spacing4_levels_match_design():
    lv = level_map(4, 4, 4)
    expect = [[0, 4, 2, 4], [4, 3, 4, 3], [2, 4, 1, 4], [4, 3, 4, 3]]
    np.testing.assert_array_equal(lv, expect)


def _cfg(**kw):
    return make_config("dacs", width=W, height=H, **kw)


def _deferred(scene):
    return np.asarray(deferred.render(scene, scene.camera,
                                      make_config("deferred", width=W, height=H)).image)


def test_threshold_zero_shades_every_pixel_and_equals_deferred():
    for scene, exact in ((flat_scene(), True), (shapes_scene(), False)):
        ref = _deferred(scene)
        f = dacs_mod.render(scene, scene.camera, _cfg(threshold=0.0))
        assert int(f.counts["shade_invocations"]) == W * H == int(f.counts["covered_pixels"])
        assert np.asarray(f.aux["shaded"]).all()
        img = np.asarray(f.image)
        if exact:
            np.testing.assert_array_equal(img, ref)
        else:
            np.testing.assert_allclose(img, ref, rtol=_ULP_RTOL, atol=0, err_msg="vs deferred")


def test_infinite_threshold_on_flat_single_id_scene_shades_one_sixteenth():
    scene = flat_scene()
    f = dacs_mod.render(scene, scene.camera, _cfg(threshold=float("inf")))
    assert int(f.counts["shade_invocations"]) * 16 == W * H
    np.testing.assert_array_equal(np.asarray(f.aux["shaded"]), np.asarray(f.aux["level"]) == 0)
    # a flat colour: interpolated means of equal values match deferred up to rounding
    np.testing.assert_allclose(np.asarray(f.image), _deferred(scene), rtol=_ULP_RTOL, atol=0)
    lv = np.asarray(f.aux["level"])
    assert lv.dtype == np.int32 and lv.shape == (H, W) and np.asarray(f.aux["shaded"]).dtype == bool


def test_threshold_sweep_is_monotone_and_compiles_once():
    scene = shapes_scene()
    cfg = _cfg()
    n = [int(dacs_mod.render(scene, scene.camera, dataclasses.replace(cfg, threshold=t))
             .counts["shade_invocations"])
         for t in (0.0, 1e-4, 1e-2, float("inf"))]
    assert n == sorted(n, reverse=True) and n[0] == W * H and n[-1] < W * H // 2
    size = program.cache_size()
    dacs_mod.render(scene, scene.camera, _cfg(threshold=0.5))  # a new threshold, same program
    assert program.cache_size() == size


# ------------------------------------------------------------------ image-lookup shading


@functools.partial(jax.jit, static_argnames=("spacing", "border"))
def _lookup_jit(image, ids, threshold, spacing, border):
    h, w = ids.shape
    flat = image.reshape(-1, 3)
    return dacs_mod.dacs_reconstruct(lambda items, live: flat[items], ids, jnp.ones((h, w), bool),
                                     threshold, chunk=64, spacing=spacing, border=border)


def _lookup(image, threshold, *, ids=None, spacing=4, border="average"):
    """DACS with the shading function an image lookup (one compile per shape and options)."""
    h, w = image.shape[:2]
    ids = np.zeros((h, w), np.int32) if ids is None else ids
    img, shaded, _, counts = _lookup_jit(jnp.asarray(image, jnp.float32),
                                         jnp.asarray(ids, jnp.int32), jnp.float32(threshold),
                                         spacing, border)
    return np.asarray(img), np.asarray(shaded), counts


def _ramp(w, h):
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    # Multiples of 1/64 in [0, 1]: averages of parents are exact in float32.
    r = (2 * x + 3 * y) / 256.0
    return np.stack([r, 0.5 * r, 0.25 + 0.25 * r], -1).astype(np.float32)


@pytest.mark.parametrize("w,h,spacing,border", [(33, 21, 4, "average"), (33, 17, 8, "average"),
                                                (32, 24, 4, "shade"), (31, 19, 8, "shade")])
def test_linear_gradient_is_reconstructed_exactly(w, h, spacing, border):
    ramp = _ramp(w, h)
    img, shaded, _ = _lookup(ramp, float("inf"), spacing=spacing, border=border)
    np.testing.assert_array_equal(img, ramp)
    if (w - 1) % spacing == 0 and (h - 1) % spacing == 0:  # only level 0 shaded
        np.testing.assert_array_equal(shaded, level_map(h, w, spacing) == 0)


@pytest.mark.parametrize("w,h", [(32, 24), (33, 21)])
def test_step_edge_is_reconstructed_exactly(w, h):
    img_ = np.full((h, w, 3), 0.2, np.float32)
    img_[:, 13:] = 0.7
    img_[9:, :] += 0.05  # a horizontal step too
    img, shaded, _ = _lookup(img_, 1e-4)  # colour variance finds the steps
    np.testing.assert_array_equal(img, img_)
    assert shaded.mean() < 0.5
    ids = np.zeros((h, w), np.int32)
    ids[:, 13:] = 1
    flat = np.where(ids[..., None] == 1, 0.7, 0.2).astype(np.float32).repeat(3, axis=-1)
    img, shaded, _ = _lookup(flat, float("inf"), ids=ids)  # the ids alone find the edge
    np.testing.assert_array_equal(img, flat)


@pytest.mark.parametrize("w,h,spacing", [(1, 1, 4), (1, 7, 4), (7, 1, 8), (5, 3, 4), (34, 22, 4),
                                         (33, 17, 8), (32, 24, 4)])
def test_borders_and_odd_sizes_are_finite(w, h, spacing):
    rng = np.random.default_rng(w * 100 + h)
    image = rng.uniform(0.0, 2.0, (h, w, 3)).astype(np.float32)
    img, shaded, counts = _lookup(image, 0.01, spacing=spacing)
    assert np.all(np.isfinite(img))
    np.testing.assert_array_equal(img[shaded], image[shaded])
    assert int(counts["shade_invocations"]) == int(shaded.sum())
    # interpolated pixels lie within the range of the image (means of parents)
    assert img.min() >= image.min() and img.max() <= image.max()


def test_each_level_is_one_launch_of_a_power_of_two_number_of_chunks():
    # Levels need different numbers of 64-lane chunks here; each launches the fewest power of
    # two of them that holds its list (dispatch's "switch"), read off its own decisions. The
    # levels have 384, 384, 768, 1536 and 3072 pixels.
    rng = np.random.default_rng(7)
    image = rng.uniform(0.0, 1.0, (64, 96, 3)).astype(np.float32)
    image[:, :40] = 0.5  # flat on the left: fewer of its pixels need shading
    _, shaded, counts = _lookup(image, 0.002)
    levels = level_map(64, 96, 4)
    assert [int(np.sum(levels == k)) for k in range(n_levels(4))] == [384, 384, 768, 1536, 3072]
    need = [int(np.sum(shaded & (levels == k))) for k in range(n_levels(4))]
    chunks = [-(-n // 64) for n in need]
    launched = [0 if c == 0 else 1 << (c - 1).bit_length() for c in chunks]
    assert len(set(chunks)) > 2 and launched != chunks, f"the case rounds up: {chunks}"
    assert int(counts["shade_invocations"]) == sum(need)
    assert int(counts["dispatch_chunks"]) == sum(launched), (need, chunks, launched)
    assert int(counts["dispatch_lanes"]) == 64 * sum(launched)
    assert int(counts["dispatch_lanes"]) < 2 * 64 * sum(chunks)


def _srgb(c):
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def _numpy_dacs(image, ids, threshold, spacing, border):
    """DACS by its rules, level by level and pixel by pixel, in float64: level 0 shaded; a
    later pixel shaded where a parent inside has another id, the parents' display luma varies
    by at least the threshold, or (border "shade") no opposite pair of parents is inside;
    else the mean of its complete opposite pairs (of the parents inside, if none is)."""
    h, w = ids.shape
    out = np.zeros((h, w, 3))
    shaded = np.zeros((h, w), bool)
    for level, pixels in enumerate(level_pixels(h, w, spacing)):
        for p in pixels:
            y, x = divmod(int(p), w)
            if level == 0:
                out[y, x], shaded[y, x] = image[y, x], True
                continue
            pairs = [[(y + dy, x + dx) for dy, dx in pair] for pair in parent_pairs(level, spacing)]
            inside = [(py, px) for pair in pairs for py, px in pair if 0 <= py < h and 0 <= px < w]
            complete = [q for pair in pairs if all(0 <= a < h and 0 <= b < w for a, b in pair)
                        for q in pair]
            lum = [float(_srgb(np.clip(out[q], 0, 1)) @ [0.25, 0.5, 0.25]) for q in inside]
            need = (np.var(lum) >= threshold or any(ids[q] != ids[y, x] for q in inside)
                    or (border == "shade" and not complete))
            if need:
                out[y, x], shaded[y, x] = image[y, x], True
            else:
                out[y, x] = np.mean([out[q] for q in (complete or inside)], axis=0)
    return out, shaded


@pytest.mark.parametrize("w,h,spacing,border", [(53, 38, 4, "average"), (53, 38, 4, "shade"),
                                                (29, 22, 8, "average")])
def test_levels_decide_and_reconstruct_as_a_numpy_reference(w, h, spacing, border):
    rng = np.random.default_rng(w + h + spacing)
    # Smooth with noise: some parents' luma varies past the threshold, some does not.
    y, x = np.mgrid[0:h, 0:w]
    base = 0.5 + 0.4 * np.sin(x / 7.0)[..., None] * np.cos(y / 5.0)[..., None]
    image = np.clip(base + rng.normal(0, 0.04, (h, w, 3)), 0, 1.2).astype(np.float32)
    ids = (rng.random((h, w)) < 0.03).astype(np.int32)
    img, shaded, counts = _lookup(image, 0.002, ids=ids, spacing=spacing, border=border)
    want, want_shaded = _numpy_dacs(image.astype(np.float64), ids, 0.002, spacing, border)
    assert 0.1 < want_shaded.mean() < 0.9, "the case shades some pixels and interpolates others"
    np.testing.assert_array_equal(shaded, want_shaded, err_msg="pixels shaded")
    np.testing.assert_allclose(img, want, rtol=1e-5, atol=1e-6, err_msg="reconstructed image")
    assert int(counts["shade_invocations"]) == int(want_shaded.sum())


def test_warp_simulation_counts():
    w = 32
    all_on = [jnp.ones((256,), bool)]
    c = simulate(all_on, w, 4)  # 8 search steps, 8 full shade steps
    assert int(c["warp_search_steps"]) == 8 and int(c["warp_shade_steps"]) == 8
    assert float(c["warp_lane_utilization"]) == 1.0
    sparse = [jnp.asarray(np.arange(256) % 8 == 0)]  # 4 of 32 per search step
    c = simulate(sparse, w, 4)
    # queue: 2 warps x 4 steps x 4 -> 16 per warp, one partial shade step per warp
    assert int(c["warp_shade_steps"]) == 2 and int(c["naive_simd_steps"]) == 16
    assert float(c["warp_shade_utilization"]) == 0.5
    assert float(c["naive_shade_utilization"]) == 4 / 32
    with pytest.raises(ValueError, match="warp width"):
        simulate(all_on, 48, 4)


def _warp_scheme_by_steps(needs, width, batches):
    """The warp scheme replayed one SIMD step at a time, as the module docstring states it:
    (search steps, shade steps, naive shade steps)."""
    search = shade = naive = 0
    for need in needs:
        need = list(map(bool, need))
        per_warp = width * batches
        for start in range(0, len(need), per_warp):
            queue = 0
            for g in range(start, min(start + per_warp, len(need)), width):
                group = need[g:g + width]
                search += 1
                naive += any(group)
                queue += sum(group)
                if queue >= width:  # a full SHADE step
                    shade, queue = shade + 1, queue - width
            shade += queue > 0  # the level's barrier drains the queue
    return search, shade, naive


@pytest.mark.parametrize("width,batches", [(32, 4), (64, 2), (32, 1)])
def test_warp_simulation_matches_a_step_by_step_replay(width, batches):
    rng = np.random.default_rng(width * 10 + batches)
    lengths = [0, 1, 31, 200, 1000, width * batches * 3 + 5]
    needs = [rng.random(n) < rng.choice([0.0, 0.05, 0.3, 0.9, 1.0]) for n in lengths]
    c = simulate([jnp.asarray(n) for n in needs], width, batches)
    want = _warp_scheme_by_steps(needs, width, batches)
    got = (int(c["warp_search_steps"]), int(c["warp_shade_steps"]),
           int(c["naive_simd_steps"]) - int(c["warp_search_steps"]))
    assert got == want, f"(search, shade, naive shade) steps {got}, replay {want}"


def test_dacs_counts_and_config_errors():
    scene = shapes_scene()
    f = dacs_mod.render(scene, scene.camera, _cfg(threshold=0.01))
    c = {k: np.asarray(v) for k, v in f.counts.items()}
    assert int(c["shade_invocations"]) == int(np.asarray(f.aux["shaded"]).sum())
    assert 0.0 < float(c["warp_lane_utilization"]) <= 1.0
    assert int(c["warp_simd_steps"]) <= int(c["naive_simd_steps"])
    for bad in ({"spacing": 2}, {"ids": "colour"}, {"luma": "hsv"}, {"threshold": -1.0},
                {"warp_width": 16}, {"border": "wrap"}):
        with pytest.raises(ValueError):
            _cfg(**bad)
