"""Object-space shading (issue 8): filter blur vs deferred, temporal stability on the stripe
shader, triangle ownership of the texture-space triangle-id map, and the MIP bias under a too
small store against a hand-worked case.

The plane scenes take the shapes, material kind, lights, name and effects of the built-in
``stripes`` scene (4x4 subdivisions), so that deferred compiles once for every test here
(compiling is the slow part on a CPU).
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.metrics import psnr, temporal_error
from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines import object_space as osp
from jaxrender.pipelines.os_sheet import LANES, build_sheet
from jaxrender.pipelines.os_texels import raster_st
from jaxrender.raster import rasterize_clip
from jaxrender.scene import MeshPart, camera_path, look_at
from jaxrender.scene.builtin import stripes
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.scene import build_scene

W = H = 32  # pixels; the plane's sheet has W shadels a side: 1 shadel per pixel
D = 2.0  # camera distance; a 90 degree field of view spans [-D, D]
_EXACT = 1e-5  # float32 rounding of barycentrics and colours


@functools.lru_cache(maxsize=1)
def stripes_scene():
    return stripes(plane_size=100.0, subdivisions=4, stripe_resolution=512.0)


@functools.lru_cache(maxsize=1)
def plane_scene():
    """A plane facing the camera that exactly fills a 90-degree view: uv [0, 1]^2 over the
    W x H pixels, the 1-texel stripe shader at W stripes, so texel (x, y) lies under pixel
    (x, y)."""
    base = stripes_scene()
    g = np.linspace(-D, D, 5)
    x, y = np.meshgrid(g, -g, indexing="xy")
    pos = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], 1)
    uv = np.stack([(x.ravel() + D) / (2 * D), (y.ravel() + D) / (2 * D)], 1)
    i = np.arange(4)[:, None] * 5 + np.arange(4)[None, :]
    faces = np.concatenate([np.stack([i, i + 5, i + 1], -1),
                            np.stack([i + 1, i + 5, i + 6], -1)]).reshape(-1, 3)
    mat = Material("stripes", albedo=(0.9, 0.9, 0.9), procedural="stripes",
                   stripe_resolution=float(W))
    return build_scene([MeshPart(pos, faces, uvs=uv)], [mat], [],
                       make_lights([((0.3, 0.4, 1.0), 2.5)], ambient=0.05), _camera(0.0, 0.0),
                       name=base.name, description=base.description)


def _camera(sx, sy):
    return look_at((sx, sy, D), (sx, sy, 0.0), fov_y_deg=90.0, near=0.1, far=10.0)


def _deferred(scene, camera):
    return np.asarray(get_pipeline("deferred").render(scene, camera,
                                                      make_config("deferred", width=W,
                                                                  height=H)).image)


def test_plane_one_texel_per_pixel_matches_deferred_within_filter_blur():
    scene = plane_scene()
    cfg = osp.ObjectSpaceConfig(width=W, height=H, sheet_resolution=W)
    # Aligned: texel centres under pixel centres, so the bilinear weights are (1, 0) and the
    # filter does not blur at all; the shadels were shaded at the very points deferred shades.
    # The bound is float32 rounding: PSNR >= 60 dB (measured: identical).
    f = osp.render(scene, scene.camera, cfg)
    d = _deferred(scene, scene.camera)
    assert float(psnr(np.clip(f.image, 0, 1), np.clip(d, 0, 1))) >= 60.0
    assert int(f.counts["shade_invocations"]) == W * H
    assert float(f.counts["mip_bias"]) == 0.0
    # Half a pixel off: every pixel sits between four shadels and the bilinear filter returns
    # their mean, i.e. exactly the 2x2 box blur of the aligned deferred image. So the bound vs
    # the shifted deferred image is the PSNR of that box blur (the blur of the filter), which
    # for the 1-texel stripes is the worst case (the stripes average to grey).
    cam = _camera(D / W, -D / W)
    fs = np.asarray(osp.render(scene, cam, cfg).image)[:-1, :-1]
    box = 0.25 * (d[:-1, :-1] + d[1:, :-1] + d[:-1, 1:] + d[1:, 1:])
    np.testing.assert_allclose(fs, box, atol=_EXACT, err_msg="object space != 2x2 box filter")
    ds = _deferred(scene, cam)[:-1, :-1]
    bound = float(psnr(np.clip(box, 0, 1), np.clip(ds, 0, 1)))
    assert float(psnr(np.clip(fs, 0, 1), np.clip(ds, 0, 1))) >= bound - 0.01


def test_too_small_store_raises_bias_and_shades_everything_visible():
    # Hand-worked: sheet 32^2 -> levels 32^2 (16 chunks), 16^2 (4 chunks), 8^2 (1 chunk). At
    # 1 shadel per pixel the LOD is 0. A store of 6 chunks: bias 0 needs level 0 (16 chunks),
    # bias 0.25 / 0.5 / 0.75 need levels 0 and 1 (trilinear, 20 chunks), bias 1 needs level 1
    # alone: 4 chunks = 256 shadels, all owned, each read by some pixel (fill 1).
    scene = plane_scene()
    cfg = osp.ObjectSpaceConfig(width=W, height=H, sheet_resolution=W, store_shadels=6 * LANES)
    f = osp.render(scene, scene.camera, cfg)
    c = {k: float(v) for k, v in f.counts.items()}
    assert c["mip_bias"] == 1.0 and c["mip_bias_steps"] == 4
    assert c["chunks_marked"] == 4 and c["chunks_allocated"] == 4
    assert c["shade_invocations"] == 256 and c["shadels_allocated"] == 256
    assert c["covered_pixels"] == W * H and c["shadels_per_pixel"] == 0.25
    assert c["chunk_fill"] == 1.0 and c["missing_taps"] == 0 and c["overflow"] == 0
    assert c["store_capacity_shadels"] == 6 * LANES and c["helper_lanes"] == 0
    # Everything visible is shaded: every tap of every pixel reads a shaded, owned shadel.
    assert c["shadels_needed"] == c["shade_invocations"] and c["unowned_taps"] == 0
    assert np.all(np.isfinite(np.asarray(f.image)))
    assert np.all(np.asarray(f.aux["mip_level"]) == 1.0)
    assert set(np.unique(np.asarray(f.aux["chunk_state"]))) == {2}


def test_unowned_taps_count_the_taps_that_read_a_shadel_no_triangle_owns():
    # The aligned plane (one shadel per pixel, LOD 0): each pixel's one tap of weight 1 reads
    # the shadel under it, so level 0's 16 chunks are all resident and each of their shadels
    # is read once. Taking the owner from every other shadel of the first chunk leaves 32
    # taps reading an unowned shadel, and those shadels are not shaded.
    scene = plane_scene()
    cfg = osp.ObjectSpaceConfig(width=W, height=H, sheet_resolution=W)
    sheet = osp.prepare(scene, cfg)
    owner = np.asarray(sheet.owner).copy()
    assert np.all(owner[:16 * LANES] >= 0), "the plane's level 0 should be owned throughout"
    owner[:LANES:2] = -1
    holed = dataclasses.replace(sheet, owner=jnp.asarray(owner))
    step = jax.jit(lambda sc, sh: osp.frame_step(sc, sh, sc.camera, cfg,
                                                  osp.empty_state(sh, cfg), jnp.bool_(True)))
    frame, _ = step(scene, holed)
    c = {k: int(np.asarray(v)) for k, v in frame.counts.items()
         if k in ("unowned_taps", "missing_taps", "overflow", "shade_invocations")}
    assert c == {"unowned_taps": 32, "missing_taps": 0, "overflow": 0,
                 "shade_invocations": W * H - 32}, c


def test_stripes_are_temporally_stabler_in_object_space_than_deferred():
    scene = stripes_scene()
    path = camera_path.pan(scene.camera, 8, 0.25, H)
    cfg = osp.ObjectSpaceConfig(width=W, height=H, shade_every=2)
    seq = osp.render_sequence(scene, path.cameras, cfg)
    o = np.clip(np.asarray(seq.image), 0, 1)
    d = np.clip(np.stack([_deferred(scene, cam) for cam, _ in path]), 0, 1)
    ref_cfg = make_config("reference", width=W, height=H, k=4)
    r = np.clip(np.stack([np.asarray(get_pipeline("reference").render(scene, cam, ref_cfg).image)
                          for cam, _ in path]), 0, 1)
    e_os, e_def = float(temporal_error(o, r)), float(temporal_error(d, r))
    assert e_os < 0.5 * e_def, (e_os, e_def)
    # Temporal decoupling: a Lambert scene is view-independent, so after frame 0 the resident
    # chunks are reused and only chunks that became visible are shaded.
    inv = np.asarray(seq.counts["shade_invocations"])
    reused = np.asarray(seq.counts["chunks_reused"])
    assert inv[0] > 0 and reused[0] == 0
    assert np.all(inv[1:] < inv[0] // 4) and np.all(reused[1:] > 0)
    assert np.all(np.asarray(seq.counts["missing_taps"]) == 0)


def _random_mesh(n=120, seed=3):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1, 1, (n, 1, 3))
    scale = np.exp(rng.uniform(np.log(0.003), np.log(0.4), (n, 1, 1)))  # many sub-texel ones
    pos = (centres + scale * rng.normal(size=(n, 3, 3))).reshape(-1, 3)
    faces = np.arange(3 * n).reshape(n, 3)
    uvs = rng.uniform(0, 1, (3 * n, 2))  # overlapping: xatlas must chart it
    mat = Material("m")
    return build_scene([MeshPart(pos, faces, uvs=uvs)], [mat], [], make_lights(ambient=0.1),
                       look_at((0, 0, 3), (0, 0, 0)), name="random")


def test_every_triangle_of_a_random_mesh_owns_a_shadel():
    scene = _random_mesh()
    cfg = osp.ObjectSpaceConfig(sheet_resolution=64)
    sheet = build_sheet(scene, cfg)
    assert sheet.sources == ("xatlas",)
    level0 = np.asarray(sheet.owner)[: sheet.level0_chunks * LANES]
    assert set(range(scene.num_triangles)) <= set(level0[level0 >= 0].tolist())


def test_texture_space_raster_follows_the_shared_rasterizer():
    # raster_st (NumPy, built once per mesh) against rasterize_clip on the same chart: a jittered
    # 7x7 grid, triangulated (no overlaps: charts never overlap), seen at 24^2 texels, so shared
    # edges exercise the top-left rule.
    rng = np.random.default_rng(0)
    g = np.linspace(0.07, 0.93, 7)  # edges at 1.68 and 22.32 texels: off the centres
    p = np.stack(np.meshgrid(g, g, indexing="xy"), -1).reshape(-1, 2)
    inner = (p > 0.08).all(1) & (p < 0.92).all(1)
    p[inner] += rng.uniform(-0.05, 0.05, (int(inner.sum()), 2))
    i = (np.arange(6)[:, None] * 7 + np.arange(6)[None, :]).ravel()
    faces = np.concatenate([np.stack([i, i + 7, i + 1], -1), np.stack([i + 1, i + 7, i + 8], -1)])
    st = p[faces]
    res = 24
    owner, hits = raster_st(st, res)
    assert hits.max() == 1
    clip = np.concatenate([st[..., :1] * 2 - 1, 1 - st[..., 1:] * 2, np.zeros(st.shape[:2] + (1,)),
                           np.ones(st.shape[:2] + (1,))], -1).reshape(-1, 4).astype(np.float32)
    n = st.shape[0]
    vis = rasterize_clip(clip, np.arange(3 * n, dtype=np.int32).reshape(n, 3), res, res)
    np.testing.assert_array_equal(owner, np.asarray(vis.tri_id))
    cons, _ = raster_st(st, res, conservative=True)
    assert np.all(cons[owner >= 0] >= 0) and (cons >= 0).sum() > (owner >= 0).sum()


def test_config_validation():
    with pytest.raises(ValueError, match="filter"):
        osp.ObjectSpaceConfig(filter="nearest")
    with pytest.raises(ValueError, match="shade_every"):
        osp.ObjectSpaceConfig(shade_every=0)


def test_allocation_computes_the_taps_once_a_bias_tried(monkeypatch):
    # The taps of the last bias tried are the ones the frame reads: carried out of the bias
    # loop, not computed a second time. Traced: once for the first bias, once for the loop's
    # body (the frame's other taps are its counts' finest-level marking).
    import jaxrender.pipelines.os_alloc as os_alloc

    scene = plane_scene()
    cfg = osp.ObjectSpaceConfig(width=W, height=H, sheet_resolution=W, store_shadels=6 * LANES)
    sheet = osp.prepare(scene, cfg)
    traced = []
    real = os_alloc.taps
    monkeypatch.setattr(os_alloc, "taps", lambda *a, **k: traced.append(1) or real(*a, **k))
    closed = jax.make_jaxpr(lambda sc, sh: osp.frame_step(
        sc, sh, sc.camera, cfg, osp.empty_state(sh, cfg), jnp.bool_(True))[0].image)
    closed(scene, sheet)
    assert len(traced) == 2, f"allocate traced the taps {len(traced)} times"
