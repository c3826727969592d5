"""The reference pipeline: the same samples as the rasterizer's own multi-sample path, exact box
filtering of a known edge, texture LOD from the sample footprint, alpha test, counts read off
the work, one compile for every camera and every k, camera paths, convergence estimate."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.pipelines import get_pipeline, make_config, program
from jaxrender.pipelines.reference import (
    DEFAULT_K,
    ReferenceConfig,
    _bary_at,
    _offset,
    convergence_psnr,
    render,
    samples_per_pass,
)
from jaxrender.raster import rasterize
from jaxrender.raster.fragments import collect_fragments, default_fragment_capacity
from jaxrender.raster.rasterize import default_clip_capacity, default_work_capacity
from jaxrender.raster import samples as sample_patterns
from jaxrender.raster.resolve import barycentrics
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene import Material, MeshPart, look_at, make_lights, world_to_clip
from jaxrender.scene.builtin import checker_image
from jaxrender.scene.camera_path import stack
from jaxrender.scene.scene import build_scene
from jaxrender.shading import shade, surface_points
from tests.pipelines.transparent_scenes import THREE, layered_quads

W, H = 48, 32
_EXACT = 1e-6  # same arithmetic, different program: float32 rounding only
EDGE_X = 30.3  # window x of quad 1's left edge (pixel 30 is 3/4 covered at k = 8)
GREY = 0.6  # quad 1's radiance: albedo 0.6, E = pi at normal incidence, Lambert


def _quad(corners, normal, material) -> MeshPart:
    pos = np.asarray(corners, np.float64)
    uvs = np.asarray([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)
    return MeshPart(pos, np.asarray([[0, 1, 2], [0, 2, 3]]), np.tile(normal, (4, 1)), uvs,
                    material=material)


def _camera(x=0.0):
    # fov 90, aspect 1.5: window x = (x_world / 1.5 / depth + 1) * W / 2 at depth 1
    return look_at((x, 0.0, 0.0), (x, 0.0, -1.0), fov_y_deg=90.0, near=0.1, far=20.0)


@pytest.fixture(scope="module")
def scene_a():
    """A textured quad receding in depth on the left (LOD varies) and an untextured grey quad
    facing the camera whose left edge lies at window x = EDGE_X, under a frontal sun."""
    edge = (EDGE_X * 2.0 / W - 1.0) * 1.5
    left = _quad([(-1.4, -1, -1), (-0.2, -1, -1), (-0.2, 1, -4), (-1.4, 1, -4)],
                 (0.0, 0.8, 0.6), 0)
    right = _quad([(edge, -2, -1), (3, -2, -1), (3, 2, -1), (edge, 2, -1)], (0.0, 0.0, 1.0), 1)
    mats = [Material("checker", albedo=(1, 1, 1), texture=0),
            Material("grey", albedo=(GREY,) * 3)]
    lights = make_lights([((0, 0, 1), np.pi)], ambient=0.0)
    return build_scene([left, right], mats, [checker_image(64, 8)], lights, _camera(),
                       name="reference_test")


def _cfg(k, **kw):
    return ReferenceConfig(width=W, height=H, k=k, **kw)


def test_config_and_registry():
    assert get_pipeline("reference").config_cls is ReferenceConfig
    assert make_config("reference", width=8, height=4, k=3).k == 3
    assert ReferenceConfig().k == DEFAULT_K == 8
    with pytest.raises(ValueError, match="k must be"):
        ReferenceConfig(k=0)


def test_offsets_are_the_stratified_pattern():
    for k in (1, 2, 3, 5, 8, 16, 33):
        want = np.asarray(sample_patterns.to_fixed(sample_patterns.stratified(k), SUBPIXEL_BITS))
        got = np.asarray(_offset(np.arange(k * k), k)).T
        np.testing.assert_array_equal(got, want, err_msg=f"k={k}")


def test_alpha_barycentrics_are_the_resolve_ones():
    """The alpha test's per-fragment barycentrics are those resolve() gives the winner."""
    cam = look_at((0, 0, 2), (0, 0, 0))
    pos = jnp.asarray([[-1, -1, 0], [1, -0.5, -1], [0, 1, 0.5]], jnp.float32)
    faces = jnp.asarray([[0, 1, 2]], jnp.int32)
    clip = world_to_clip(pos, cam, 8 / 6)
    tri = jnp.zeros((6, 8), jnp.int32)
    want = barycentrics(tri, clip, faces, 8, 6, jnp.asarray([0.25, 0.75], jnp.float32))
    yy, xx = np.mgrid[0:6, 0:8]
    got = _bary_at(tri.reshape(-1), jnp.asarray(xx.ravel() + 0.25, jnp.float32),
                   jnp.asarray(yy.ravel() + 0.75, jnp.float32), clip, faces, 8, 6)
    for name, a, b in zip(("bary", "dbary_dx", "dbary_dy"), got, want):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b).reshape(-1, 3), atol=1e-6,
                                   err_msg=name)


def test_equals_rasterizer_samples_shaded_and_averaged(scene_a):
    """Per sample: the rasterizer's own S-sample visibility, surface points with the
    derivatives scaled to the sample spacing (1/k), shade(), then the mean."""
    k, cam = 2, _camera()
    frame = render(scene_a, cam, _cfg(k))
    vis = rasterize(scene_a.positions, scene_a.faces, cam, W, H,
                    sample_offsets=sample_patterns.stratified(k))

    @jax.jit
    def shade_sample(tri, bary, ddx, ddy):
        pts = surface_points(scene_a, cam, tri.reshape(-1), bary.reshape(-1, 3),
                             ddx.reshape(-1, 3) / k, ddy.reshape(-1, 3) / k)
        return shade(pts, scene_a)

    acc = jnp.zeros((H * W, 3), jnp.float32)
    for s in range(k * k):
        acc = acc + shade_sample(vis.tri_id[s], vis.bary[s], vis.dbary_dx[s], vis.dbary_dy[s])
    want = np.asarray(acc * (1.0 / (k * k))).reshape(H, W, 3)
    np.testing.assert_allclose(np.asarray(frame.image), want, atol=_EXACT, rtol=_EXACT,
                               err_msg="reference vs rasterize(stratified) + shade")

    covered = np.asarray(vis.tri_id) >= 0
    c = {key: int(v) for key, v in frame.counts.items()}
    assert c["shade_invocations"] == covered.sum()
    assert c["covered_pixels"] == covered.any(axis=0).sum()
    assert c["fragments"] == int(vis.counts["fragments"])
    assert c["samples_per_pixel"] == k * k
    assert c["lanes"] >= c["shade_invocations"]
    assert c["helper_lanes"] == c["lanes"] - c["shade_invocations"]
    np.testing.assert_array_equal(np.asarray(frame.aux["coverage"]), covered.any(axis=0))


def test_the_one_launch_pass_equals_the_chunked_dispatch(scene_a):
    """chunk 0 shades each pass of samples in one launch: its covered samples compacted into
    half the pass's lanes when at most half are covered, else every sample in place; chunk =
    a pass's lanes compacts them into one launch of that size: the same image and
    invocations, and lanes read off each launch."""
    k, cam, per_pass = 3, _camera(), 4
    one = render(scene_a, cam, _cfg(k, samples_per_pass=per_pass))
    chunked = render(scene_a, cam, _cfg(k, samples_per_pass=per_pass, chunk=per_pass * W * H))
    np.testing.assert_array_equal(np.asarray(one.image), np.asarray(chunked.image),
                                  err_msg="image: one launch vs the chunked dispatch")
    for key in ("shade_invocations", "chunks"):
        assert int(one.counts[key]) == int(chunked.counts[key]), key
    assert int(one.counts["chunks"]) == 3  # 9 samples in passes of 4: 3 launches
    vis = rasterize(scene_a.positions, scene_a.faces, cam, W, H,
                    sample_offsets=sample_patterns.stratified(k))
    covered = (np.asarray(vis.tri_id) >= 0).reshape(k * k, -1)
    full = per_pass * W * H
    want = 0
    for p in range(3):  # the last pass holds one live sample and three dead ones
        c = int(covered[p * per_pass:(p + 1) * per_pass].sum())
        want += 0 if c == 0 else full // 2 if c <= full // 2 else full
    assert int(one.counts["lanes"]) == want
    assert int(chunked.counts["lanes"]) == 3 * full


@pytest.mark.parametrize("kind", ["opaque", "alpha", "transparent"])
def test_passes_of_any_size_give_the_same_image(scene_a, kind):
    """The samples of a pass share one traversal and one launch (and one transparent fragment
    list, dispatch and sort); the image and the work that depends on the samples alone are the
    same bits for any pass size, dead samples (9 in passes of 4 or 8) included; lanes are the
    passes' launches, whole."""
    scene = {"opaque": scene_a, "alpha": _alpha_scene(),
             "transparent": layered_quads(THREE, (2, 0, 1))}[kind]
    k, cam = 3, _camera(0.07) if kind != "transparent" else scene.camera
    # Passes of 8 are the automatic choice at this size: the default config is the program
    # other tests of the scene compile (test_equals_rasterizer_samples_shaded_and_averaged,
    # test_alpha_test_discards_before_the_depth_test), not one more of its own.
    assert samples_per_pass(_cfg(k)) == 8
    configs = {1: _cfg(k, samples_per_pass=1), 4: _cfg(k, samples_per_pass=4), 8: _cfg(k)}
    frames = {n: render(scene, cam, cfg) for n, cfg in configs.items()}
    sums = ("transparent_invocations", "transparent_fragments", "transparent_bytes",
            "transparent_layers_max") if kind == "transparent" else ()
    for n in (4, 8):
        np.testing.assert_array_equal(np.asarray(frames[n].image), np.asarray(frames[1].image),
                                      err_msg=f"image: passes of {n} vs one sample a pass")
        for key in ("shade_invocations", "fragments", "covered_pixels", "samples_per_pixel",
                    *sums):
            assert int(frames[n].counts[key]) == int(frames[1].counts[key]), (n, key)
        passes = -(-k * k // n)
        if kind != "transparent":  # one launch a pass, of half its lanes or all of them
            lanes = int(frames[n].counts["lanes"])
            assert passes * n * W * H // 2 <= lanes <= passes * n * W * H, n
            assert int(frames[n].counts["chunks"]) == passes, n
    for n, frame in frames.items():  # the layers' dispatch counts as shading lanes too
        assert int(frame.counts["helper_lanes"]) >= 0, (n, int(frame.counts["helper_lanes"]))
    # a pass lists each bounding-box pixel once for all of its samples
    assert int(frames[8].counts["work_items"]) < int(frames[1].counts["work_items"])
    with pytest.raises(ValueError, match="samples_per_pass must be"):
        _cfg(2, samples_per_pass=-1)


def test_box_filter_of_a_known_edge(scene_a):
    """Pixel 30 holds the edge at x = 30.3: 6 of the 8 cell columns are covered at k = 8."""
    img = np.asarray(render(scene_a, _camera(), _cfg(8)).image)
    np.testing.assert_allclose(img[:, 31:], GREY, rtol=1e-5, err_msg="inside the quad")
    np.testing.assert_allclose(img[:, 30], 0.75 * GREY, rtol=1e-5, err_msg="edge pixel")
    np.testing.assert_array_equal(img[:, 25:30], 0.0, err_msg="background")


def test_lod_follows_the_sample_footprint(scene_a):
    """The checker, minified on the receding quad, is filtered at the sample's footprint: more
    samples means sharper lookups each, yet the box-filtered result converges."""
    cam = _camera()
    imgs = {k: np.asarray(render(scene_a, cam, _cfg(k)).image[:, :20]) for k in (1, 4, 8)}
    assert np.abs(imgs[8] - imgs[4]).mean() < np.abs(imgs[4] - imgs[1]).mean()


def test_one_compile_for_any_camera_and_k(scene_a):
    render(scene_a, _camera(), _cfg(2))
    before = program.cache_size()
    for x, k in ((0.1, 2), (-0.2, 3), (0.05, 8)):
        render(scene_a, _camera(x), _cfg(k))
    assert program.cache_size() == before


def test_camera_path_equals_frame_by_frame(scene_a):
    cams = [_camera(0.0), _camera(0.15)]
    frames = get_pipeline("reference").render_sequence(scene_a, stack(cams), _cfg(2))
    assert frames.image.shape == (2, H, W, 3)
    assert frames.counts["shade_invocations"].shape == (2,)
    for t, cam in enumerate(cams):
        one = render(scene_a, cam, _cfg(2))
        np.testing.assert_allclose(np.asarray(frames.image[t]), np.asarray(one.image),
                                   atol=_EXACT, err_msg=f"frame {t}")
        assert int(frames.counts["shade_invocations"][t]) == int(one.counts["shade_invocations"])


def test_convergence_estimate(scene_a):
    cam = _camera()
    coarse = convergence_psnr(scene_a, cam, _cfg(2))
    fine = convergence_psnr(scene_a, cam, _cfg(8))
    assert np.isfinite(coarse) and fine > coarse + 6.0, (coarse, fine)
    frame = render(scene_a, cam, _cfg(8, convergence=True))
    assert float(frame.counts["convergence_psnr"]) == pytest.approx(fine, abs=1e-4)


def _alpha_scene():
    """An alpha-tested quad, transparent on its left half, in front of a red quad."""
    tex = np.ones((64, 64, 4))
    tex[:, :32, 3] = 0.0  # u < 0.5 transparent
    front = _quad([(-2, -2, -1), (2, -2, -1), (2, 2, -1), (-2, 2, -1)], (0, 0, 1), 0)
    back = _quad([(-4, -4, -2), (4, -4, -2), (4, 4, -2), (-4, 4, -2)], (0, 0, 1), 1)
    mats = [Material("leaf", albedo=(0.9, 0.9, 0.9), texture=0, alpha_tested=True,
                     alpha_cutoff=0.5),
            Material("red", albedo=(0.8, 0.1, 0.1))]
    return build_scene([front, back], mats, [tex], make_lights([((0, 0, 1), np.pi)]),
                       _camera(), name="alpha_test")


def test_alpha_test_runs_on_covered_samples_of_tested_triangles_only(scene_a):
    """Skipped work stays skipped: the alpha test runs once per covered sample of an
    alpha-tested triangle (the front quad, triangles 0 and 1), counted off its launches, not
    on the pass's bounding-box pixels times its samples; a scene without the test runs none."""
    scene, cam, k = _alpha_scene(), _camera(0.07), 3
    frames = {n: render(scene, cam, _cfg(k, samples_per_pass=n)) for n in (1, 4)}
    clip = world_to_clip(scene.positions, cam, W / H)
    offsets = sample_patterns.to_fixed(sample_patterns.stratified(k), SUBPIXEL_BITS)
    # The fragment list of each sample, on its own: ``fragments``' core with the sample's
    # offset an argument, so one compile serves the 9 samples (the public entry takes the
    # offset as a static argument: 9 compiles). Its default capacities, its overflow checked.
    n_tris = scene.faces.shape[0]
    cap = default_fragment_capacity(W, H)
    one_sample = jax.jit(lambda c, f, off: collect_fragments(
        c, f, W, H, cap, False, off, default_work_capacity(n_tris, W, H),
        default_clip_capacity(n_tris)))
    want = 0
    for off in offsets:
        fr = one_sample(clip, scene.faces, jnp.asarray(off, jnp.int32))
        assert 0 < int(fr.count) <= cap, (off, int(fr.count))
        tri = np.asarray(fr.tri)[np.asarray(fr.valid)]
        want += int(np.sum(np.isin(tri, (0, 1))))
    assert want > 0
    for n, frame in frames.items():
        assert int(frame.counts["alpha_invocations"]) == want, n
        assert want < int(frame.counts["work_items"]) * min(n, k * k), n
    assert int(render(scene_a, cam, _cfg(2)).counts["alpha_invocations"]) == 0


def test_alpha_test_discards_before_the_depth_test():
    """An alpha-tested quad, transparent on its left half, in front of a red quad: the left
    half of the image is the red quad, the right half the front quad."""
    scene = _alpha_scene()
    assert scene.effects.alpha_test
    img = np.asarray(render(scene, _camera(), _cfg(4)).image)
    np.testing.assert_allclose(img[:, : W // 2 - 4], np.broadcast_to([0.8, 0.1, 0.1], (H, 20, 3)),
                               rtol=1e-5, err_msg="seen through the discarded half")
    np.testing.assert_allclose(img[:, W // 2 + 4:], 0.9, rtol=1e-5, err_msg="opaque half")
    # all fragments discarded (cutoff above any alpha): only the red quad remains
    opaque_never = dataclasses.replace(scene, materials=dataclasses.replace(
        scene.materials, alpha_cutoff=scene.materials.alpha_cutoff.at[0].set(2.0)))
    img2 = np.asarray(render(opaque_never, _camera(), _cfg(4)).image)
    np.testing.assert_allclose(img2, np.broadcast_to([0.8, 0.1, 0.1], (H, W, 3)), rtol=1e-5)
