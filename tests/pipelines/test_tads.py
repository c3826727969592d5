"""Texture-aligned deferred shading (issue 20): the hand-worked aligned quad, the neighbour rule
against a NumPy oracle on random scenes, the sub-texel bits of the physical position, the
filter against NumPy bilinear filtering at magnification, the reduced shading rate and its
staleness weights, and the refusals.

The plane is object_space's test plane (tests/pipelines/test_object_space.py): a quad that
fills a 90-degree view exactly, uv [0, 1]^2 over W x H pixels, so chart point (s, t) of pixel
(x, y) is ((x + 0.5) / W, (y + 0.5) / H).
"""

from __future__ import annotations

import dataclasses
import jax
import numpy as np
import pytest

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines import tads
from jaxrender.pipelines.os_marking import footprint, taps
from jaxrender.pipelines.os_sheet import CHUNK, LANES
from jaxrender.pipelines.tads_layout import (SUBTEXEL_BITS, check_charts, object_label,
                                             pack_virtual)
from jaxrender.pipelines.tads_samples import decode, footprint_texels, geometry_pass
from jaxrender.pipelines.visibility import visibility
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.scene import build_scene
from tests.pipelines.test_object_space import (D, H, W, _camera, _deferred, _random_mesh,
                                               plane_scene, stripes_scene)
from tests.pipelines.transparent_scenes import layered_quads, quad

_EXACT = 1e-5  # float32 rounding of barycentrics and colours


def stepper(scene, cfg):
    """The pipeline's step for one scene and config, jitted: (state, camera, t) -> (frame,
    state), the prepared static data and the initial state."""
    pipe = get_pipeline("tads")
    static = pipe.prepare(scene, cfg)
    step = jax.jit(lambda state, cam, t: pipe.step(scene, static, state, cam, t, cfg))
    return step, static, pipe.init(scene, static, scene.camera, cfg)


def _counts(frame) -> dict:
    return {k: float(np.asarray(v)) for k, v in frame.counts.items()}


def test_aligned_quad_shades_each_covered_texel_exactly_once():
    # Hand-worked: a 32^2 sheet on a 32x32 view, texel centres under pixel centres. Every
    # bilinear footprint is one texel (fractions 0): 1024 texels, each shaded by its own
    # pixel, none dropped by the rule and none shaded twice. The image is deferred's: the
    # texels were shaded at the very points deferred shades.
    scene = plane_scene()
    cfg = tads.TadsConfig(width=W, height=H, sheet_resolution=W)
    f = tads.render(scene, scene.camera, cfg)
    c = _counts(f)
    assert c["covered_pixels"] == W * H
    assert c["shade_invocations"] == W * H and c["texels_shaded"] == W * H
    assert c["pixels_shading_1"] == W * H and c["footprint_1_texels"] == W * H
    assert c["duplicates_removed"] == 0 and c["duplicates_missed"] == 0
    assert c["missing_taps"] == 0 and c["overflow"] == 0
    assert c["gbuffer_bytes"] == W * H * (4 * 4 + 4)  # position 2 x int32, gradient 2 x f32, depth
    np.testing.assert_allclose(np.asarray(f.image), _deferred(scene, scene.camera), atol=_EXACT,
                               err_msg="aligned tads != deferred")


def footprint_of(scene, cfg) -> np.ndarray:
    """int32[H, W, K]: the texels each pixel's filter reads (-1 none), from the G-buffer."""
    static = tads.prepare(scene, cfg)
    vis = visibility(scene, scene.camera, cfg)
    fp = decode(geometry_pass(scene, static, vis, cfg.aniso_taps), static, cfg.aniso_taps)
    texel, _, _ = footprint_texels(fp, static, cfg.aniso_taps)
    return np.asarray(texel).reshape(cfg.height, cfg.width, cfg.taps_per_pixel)


def rule_oracle(texels: np.ndarray) -> dict:
    """The neighbour rule in NumPy, pixel by pixel: texels int32[H, W, K] (-1 none) -> the mask
    of texels each pixel shades, and what the rule removed and missed."""
    h, w, k = texels.shape
    mask = np.zeros((h, w), np.int64)
    removed, shaded = 0, []
    for y in range(h):
        for x in range(w):
            claimed = set()
            for dy, dx in ((-1, 0), (-1, -1), (0, -1)):
                if y + dy >= 0 and x + dx >= 0:
                    claimed |= set(texels[y + dy, x + dx][texels[y + dy, x + dx] >= 0].tolist())
            mine = []
            for j, t in enumerate(texels[y, x].tolist()):
                if t < 0 or t in mine:
                    continue
                mine.append(t)
                if t in claimed:
                    removed += 1
                else:
                    mask[y, x] |= 1 << j
                    shaded.append(t)
    return {"mask": mask, "removed": removed, "shaded": shaded,
            "missed": len(shaded) - len(set(shaded))}


@pytest.mark.parametrize("name,aniso", [("random", 1), pytest.param("random", 3,
                                                                    marks=pytest.mark.slow)])
def test_rule_matches_numpy_oracle_and_every_needed_texel_is_shaded(name, aniso):
    scene = _random_mesh(n=80, seed=7)
    cfg = tads.TadsConfig(width=40, height=24, sheet_resolution=64, aniso_taps=aniso)
    f = tads.render(scene, scene.camera, cfg)
    c = _counts(f)
    texels = footprint_of(scene, cfg)
    o = rule_oracle(texels)
    np.testing.assert_array_equal(np.asarray(f.aux["sample_mask"]), o["mask"],
                                  err_msg="mask != NumPy rule")
    assert c["duplicates_removed"] == o["removed"], (c["duplicates_removed"], o["removed"])
    assert c["duplicates_missed"] == o["missed"], (c["duplicates_missed"], o["missed"])
    assert c["shade_invocations"] == len(o["shaded"])
    assert c["texels_shaded"] == len(set(o["shaded"]))
    needed = set(texels[texels >= 0].tolist())
    assert needed == set(o["shaded"]), "a texel some pixel reads is not shaded"
    assert c["missing_taps"] == 0 and o["missed"] > 0 and o["removed"] > 0
    cls = np.asarray(f.aux["sample_class"])
    for k in range(1, 4 * aniso + 1):
        assert c[f"pixels_shading_{k}"] == np.sum(cls == k), k
    assert np.sum(np.asarray(f.aux["duplicates"])) >= c["duplicates_missed"]


def test_eight_subtexel_bits_reproduce_the_filter_of_the_exact_position():
    # The G-buffer keeps 8 fractional bits per axis: the stored position is within half a
    # 1/256 step of the exact one, and the taps read from it are those of the exact chart point
    # (the filter's fractions are 8-bit anyway): same texels, weights within 1/256 (a tie
    # rounded the other way), the same in all but a few taps.
    scene = _random_mesh(n=80, seed=7)
    cfg = tads.TadsConfig(width=40, height=24, sheet_resolution=64)
    static = tads.prepare(scene, cfg)
    vis = visibility(scene, scene.camera, cfg)
    n = cfg.width * cfg.height
    flat = lambda a: np.asarray(a).reshape((n,) + a.shape[2:])  # noqa: E731
    fp = footprint(scene, static.sheet, *(jax.numpy.asarray(flat(a)) for a in
                                          (vis.tri_id, vis.bary, vis.dbary_dx, vis.dbary_dy)))
    exact = taps(fp, static.sheet, jax.numpy.float32(0.0), "bilinear", 1)
    stored = decode(geometry_pass(scene, static, vis, 1), static, 1)
    cov = np.asarray(fp.covered)
    assert np.array_equal(np.asarray(stored.covered), cov)
    assert np.array_equal(np.asarray(stored.obj)[cov], np.asarray(fp.obj)[cov])
    res = np.asarray(static.sheet.obj_res)[np.asarray(fp.obj)][:, None]
    err = np.abs(np.asarray(stored.st) - np.asarray(fp.st)) * res
    assert err[cov].max() <= 2.0 ** -(SUBTEXEL_BITS + 1) + 1e-6, err[cov].max()
    texel, weight, _ = footprint_texels(stored, static, 1)
    ex_texel = np.where(np.asarray(exact.weight) > 0,
                        np.asarray(exact.chunk) * LANES + np.asarray(exact.lane), -1)
    same = np.all(np.asarray(texel) == ex_texel, axis=1)
    assert same[cov].mean() >= 0.99, same[cov].mean()
    dw = np.abs(np.asarray(weight) - np.asarray(exact.weight))[cov & same]
    assert dw.max() <= 1.0 / 256 + 1e-6, dw.max()


def _sheet_index(static, x, y):
    """Virtual texel ids of level-0 texels (x, y) of object 0."""
    res = int(np.asarray(static.sheet.obj_res)[0])
    base = int(np.asarray(static.sheet.obj_base)[0, 0])
    v = base + (y // CHUNK) * (res // CHUNK) + x // CHUNK
    return v * LANES + (y % CHUNK) * CHUNK + x % CHUNK


def bilinear_oracle(colour, static, age=None, staleness=0.0, shift=0.0):
    """NumPy bilinear filtering of object 0's level-0 texels at every pixel centre of the plane
    seen ``shift`` pixels right and down (clamp to edge), tap weights times
    1 / (1 + staleness * age) renormalised."""
    res = int(np.asarray(static.sheet.obj_res)[0])
    ys, xs = np.mgrid[0:H, 0:W]
    tx, ty = (xs + 0.5 + shift) / W * res - 0.5, (ys + 0.5 + shift) / H * res - 0.5
    x0, y0 = np.floor(tx).astype(int), np.floor(ty).astype(int)
    fx, fy = tx - x0, ty - y0
    acc, total = np.zeros((H, W, 3)), np.zeros((H, W, 1))
    for dy, wy in ((0, 1 - fy), (1, fy)):
        for dx, wx in ((0, 1 - fx), (1, fx)):
            idx = _sheet_index(static, np.clip(x0 + dx, 0, res - 1), np.clip(y0 + dy, 0, res - 1))
            wgt = (wx * wy)[..., None]
            if age is not None:
                wgt = wgt / (1.0 + staleness * age[idx][..., None])
            acc += wgt * colour[idx]
            total += wgt
    return acc / total


def test_magnification_equals_numpy_bilinear_of_the_shaded_texels():
    # An 8^2 sheet over 32x32 pixels: 4 pixels a texel, LOD clamped to level 0, fractions in
    # eighths (exact in 8 bits).
    scene = plane_scene()
    cfg = tads.TadsConfig(width=W, height=H, sheet_resolution=8)
    step, static, state = stepper(scene, cfg)
    frame, tex = step(state, scene.camera, jax.numpy.int32(0))
    colour = np.asarray(tex.colour, np.float64)
    want = bilinear_oracle(colour, static)
    np.testing.assert_allclose(np.asarray(frame.image), want, atol=_EXACT,
                               err_msg="tads filter != NumPy bilinear of the shaded texels")
    assert float(frame.counts["texels_shaded"]) == 64
    assert float(frame.counts["duplicates_missed"]) == 0


def test_shade_every_two_shades_the_scheduled_tiles_and_down_weights_stale_taps():
    # A 32^2 sheet (4 x 4 tiles of 8 x 8) under a still camera a quarter pixel off the texel
    # grid (so every pixel mixes two texels a side). Frame 0 shades every texel (none was ever
    # shaded); frame 1 shades the tiles with (cx + cy) % 2 == 1 only, 8 tiles = 512 texels; the
    # other texels keep frame 0's value and age 1, so their taps weigh 1 / (1 + staleness).
    scene = plane_scene()
    shift = 0.25
    cam = _camera(2 * D / W * shift, -2 * D / H * shift)
    cfg = tads.TadsConfig(width=W, height=H, sheet_resolution=32, shade_every=2, staleness=3.0)
    step, static, state = stepper(scene, cfg)
    f0, s0 = step(state, cam, jax.numpy.int32(0))
    f1, s1 = step(s0, cam, jax.numpy.int32(1))
    at0, at1 = np.asarray(s0.frame), np.asarray(s1.frame)
    ids = _sheet_index(static, *np.meshgrid(np.arange(32), np.arange(32), indexing="xy"))
    assert np.all(at0[ids] == 0), "frame 0 left a texel unshaded"
    tile = (np.arange(32)[None, :] // CHUNK + np.arange(32)[:, None] // CHUNK) % 2
    np.testing.assert_array_equal(at1[ids], np.where(tile == 1, 1, 0),
                                  err_msg="frame 1 did not shade exactly the scheduled tiles")
    assert float(f1.counts["texels_shaded"]) == 512 == float(f1.counts["shade_invocations"])
    assert float(f0.counts["stale_taps"]) == 0 and float(f1.counts["stale_taps"]) > 0
    colour = np.asarray(s1.colour, np.float64)
    age = 1 - at1.astype(np.float64)
    want = bilinear_oracle(colour, static, age, staleness=3.0, shift=shift)
    np.testing.assert_allclose(np.asarray(f1.image), want, atol=_EXACT,
                               err_msg="stale taps not weighted 1 / (1 + staleness * age)")
    plain = bilinear_oracle(colour, static, shift=shift)
    np.testing.assert_allclose(np.asarray(f0.image), plain, atol=_EXACT,
                               err_msg="frame 0 (all fresh) != plain bilinear")
    assert np.abs(want - plain).max() > 1e-2, "the staleness weights changed nothing here"


def aniso_oracle(colour, static, fp, n):
    """NumPy anisotropic filtering from decoded footprints (object 0): ``n`` bilinear taps along
    the gradient at the LOD of max(thickness, |gradient| / n), nearest level, 8-bit fractions,
    clamp to edge, each weighing 1 / n."""
    res = int(np.asarray(static.sheet.obj_res)[0])
    top = int(np.asarray(static.sheet.obj_levels)[0]) - 1
    base = np.asarray(static.sheet.obj_base)[0]
    st = np.asarray(fp.st, np.float64)
    ax, ac = np.asarray(fp.dst_dx, np.float64), np.asarray(fp.dst_dy, np.float64)
    major = np.linalg.norm(ax, axis=1) * res
    minor = np.linalg.norm(ac, axis=1) * res
    lod = np.log2(np.maximum(np.maximum(minor, major / n), 1e-20))
    lod = np.clip(np.round(lod * 256) / 256, 0, top)
    level = np.floor(lod + 0.5).astype(int)
    rl = (res >> level).astype(np.float64)
    out = np.zeros((st.shape[0], 3))
    for i in range(n):
        p = st + ax * ((i + 0.5) / n - 0.5)
        tx, ty = p[:, 0] * rl - 0.5, p[:, 1] * rl - 0.5
        x0, y0 = np.floor(tx), np.floor(ty)
        fx, fy = np.round((tx - x0) * 256) / 256, np.round((ty - y0) * 256) / 256
        for dy, wy in ((0, 1 - fy), (1, fy)):
            for dx, wx in ((0, 1 - fx), (1, fx)):
                x = np.clip(x0 + dx, 0, rl - 1).astype(int)
                y = np.clip(y0 + dy, 0, rl - 1).astype(int)
                cps = (rl // CHUNK).astype(int)
                v = base[level] + (y // CHUNK) * cps + x // CHUNK
                out += (wx * wy / n)[:, None] * colour[v * LANES + (y % CHUNK) * CHUNK + x % CHUNK]
    return out


@pytest.mark.slow  # its own program on a 256^2 sheet: the heaviest test of the file
def test_anisotropic_taps_are_claimed_shaded_and_filtered_as_specified():
    # The stripes plane receding to the horizon: footprints many times longer than wide. Four
    # taps along the gradient, each bilinear at the LOD of the thickness (or a quarter of the
    # length): up to 16 texels a pixel, all of them claimed by the unique-sample pass, so none is
    # read unshaded; the image is the NumPy filter of the shaded texels.
    scene = stripes_scene()
    cfg = tads.TadsConfig(width=32, height=18, sheet_resolution=256, aniso_taps=4)
    step, static, state = stepper(scene, cfg)
    frame, tex = step(state, scene.camera, jax.numpy.int32(0))
    c = _counts(frame)
    assert c["missing_taps"] == 0
    assert sum(c[f"footprint_{k}_texels"] for k in range(5, 17)) > 0, "no tap added a texel"
    texels = footprint_of(scene, cfg)
    o = rule_oracle(texels)
    np.testing.assert_array_equal(np.asarray(frame.aux["sample_mask"]), o["mask"],
                                  err_msg="anisotropic mask != NumPy rule")
    assert set(texels[texels >= 0].tolist()) == set(o["shaded"])
    vis = visibility(scene, scene.camera, cfg)
    fp = decode(geometry_pass(scene, static, vis, 4), static, 4)
    cov = np.asarray(fp.covered)
    want = aniso_oracle(np.asarray(tex.colour, np.float64), static, fp, 4)
    got = np.asarray(frame.image).reshape(-1, 3)
    close = np.all(np.abs(got - want) <= _EXACT, axis=1)
    # float32 against float64: a fraction or LOD on a rounding tie may go the other way.
    assert close[cov].mean() >= 0.99, close[cov].mean()
    assert np.abs(got - want)[cov].max() <= 0.05


def test_unsupported_inputs_are_refused_naming_the_object():
    scene = plane_scene()
    label = object_label(scene, 0, 32)
    # Largest first: object 1's 64^2 fills the 64^2 texture, object 0 is the first left out.
    with pytest.raises(ValueError, match="object 0 of scene 'stripes' .*does not fit the 64"):
        pack_virtual([32, 64, 32], [label, "object 1", "object 2"], size=64)
    assert pack_virtual([32, 32, 32, 32], ["a", "b", "c", "d"], size=64).tolist() == \
        [[0, 0], [32, 0], [0, 32], [32, 32]]
    sheet = tads.prepare(scene, tads.TadsConfig(sheet_resolution=16)).sheet
    bad = dataclasses.replace(sheet, corner_st=sheet.corner_st.at[3, 1].set(np.nan))
    with pytest.raises(ValueError, match="object 0 of scene .* has no usable UV chart"):
        check_charts(scene, bad)
    flat = dataclasses.replace(sheet, corner_st=sheet.corner_st.at[5].set(0.5))
    with pytest.raises(ValueError, match="no chart area"):
        check_charts(scene, flat)


def test_a_tiny_object_is_checked_at_its_own_scale():
    # A 1e-5 quad beside an 8 x 8 one: its triangles' areas are ~1e-12 of the large quad's,
    # under the 1e-9 that a scene-wide scale lets through, so its flat chart is caught only
    # when each object is measured against its own largest triangle.
    scene = build_scene([quad(-2.0, 0, size=(8.0, 8.0)), quad(0.0, 0, size=(1e-5, 1e-5))],
                        [Material("grey", albedo=(0.5, 0.5, 0.5))], [],
                        make_lights([], ambient=1.0), layered_quads([]).camera, name="tiny")
    sheet = tads.prepare(scene, tads.TadsConfig(sheet_resolution=16)).sheet
    assert int(sheet.obj_res[1]) > 0, "the tiny quad has a sheet to check"
    tiny = np.flatnonzero(np.asarray(scene.tri_object) == 1)
    flat = dataclasses.replace(sheet, corner_st=sheet.corner_st.at[tiny].set(0.5))
    with pytest.raises(ValueError, match="object 1 of scene 'tiny' .*no chart area"):
        check_charts(scene, flat)


def test_config_refusals():
    with pytest.raises(ValueError, match="staleness"):
        make_config("tads", staleness=0.5)
    with pytest.raises(ValueError, match="texel_density"):
        make_config("tads", sheet_resolution=64, texel_density=32.0)
    with pytest.raises(ValueError, match="aniso_taps"):
        make_config("tads", aniso_taps=8)
    make_config("tads", shade_every=2, staleness=0.5)
