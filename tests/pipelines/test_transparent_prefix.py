"""The transparent pass reads only its fragment list's filled prefix: the front test and its
work list (``front_work``) against NumPy over the whole list, the composite with ``live``
against the composite of the whole list, and the one-launch pass (``blend_on_prefix``) against
the chunked one, on random lists whose counts fall on both sides of the prefix lengths."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.pipelines import make_config
from jaxrender.pipelines.transparency import (BlendSettings, Layers, blend_on_prefix, composite,
                                              composite_list, front_work, settings_of,
                                              shade_layers)
from jaxrender.pipelines.visibility import clip_vertices, points_at
from jaxrender.raster.fragments import Fragments
from jaxrender.scene.effects import BLEND_ADDITIVE, BLEND_OVER
from jaxrender.sorting import prefix_sizes
from tests.pipelines.transparent_scenes import layered_quads, THREE

N_PIX = 64
N = 1200  # list capacity: prefix lengths 150, 225, 300, 450, 600, 900, 1200
COUNTS = [0, 1, 150, 151, 599, 901, 1200]


def _fragments(count: int, rng) -> Fragments:
    """A list of ``count`` fragments (pixel, triangle, depth), the entries past it empty as the
    rasterizer leaves them (invalid)."""
    live = np.arange(N) < count
    return Fragments(
        pixel=jnp.asarray(np.where(live, rng.integers(0, N_PIX, N), 0), jnp.int32),
        tri=jnp.asarray(np.where(live, rng.integers(1, 4, N), 0), jnp.int32),
        depth=jnp.asarray(np.where(live, rng.random(N), 0.0), jnp.float32),
        valid=jnp.asarray(live),
        count=jnp.int32(count))


def test_front_work_lists_the_fragments_in_front_of_the_opaque_depth():
    listed = jax.jit(lambda fr, opaque: front_work(fr, opaque, N_PIX))  # one compile, every count
    for count in COUNTS:
        rng = np.random.default_rng(count)
        fr = _fragments(count, rng)
        if count:  # the last fragment in front: a prefix one entry short would miss it
            fr = dataclasses.replace(fr, depth=fr.depth.at[count - 1].set(-1.0))
        opaque = rng.random(N_PIX).astype(np.float32)
        front, work = listed(fr, jnp.asarray(opaque))
        pixel, depth = np.asarray(fr.pixel), np.asarray(fr.depth)
        want = (np.arange(N) < count) & (depth < opaque[pixel])
        np.testing.assert_array_equal(np.asarray(front), want, err_msg=f"front, count {count}")
        assert int(work.count) == want.sum(), (count, int(work.count), want.sum())
        items = np.asarray(work.items)
        np.testing.assert_array_equal(items[:want.sum()], np.flatnonzero(want),
                                      err_msg=f"work list, count {count}")
        np.testing.assert_array_equal(items[want.sum():], 0, err_msg=f"padding, count {count}")


@pytest.mark.parametrize("settings", [BlendSettings(), BlendSettings(layers=2),
                                      BlendSettings(order="submission"),
                                      BlendSettings(oit="weighted")],
                         ids=["sorted", "two_layers", "submission", "weighted"])
def test_the_composite_of_the_filled_prefix_is_that_of_the_whole_list(settings):
    # Triangles 2, 4 and 6 of the three-quad scene: over, additive and over materials.
    scene = layered_quads(THREE)
    modes = np.asarray(scene.materials.blend)[np.asarray(scene.tri_material)]
    assert {BLEND_OVER, BLEND_ADDITIVE} <= set(modes[[2, 4, 6]].tolist())
    whole_list = jax.jit(lambda layers, bg: composite_list(scene, layers, bg, settings))
    on_prefix = jax.jit(lambda layers, bg: composite(scene, layers, bg, settings))
    # The sorted composite blends each pixel's layers in one order: equal bit for bit. The
    # weighted one sums them, and XLA may fuse the branch's sums differently: a few ulp.
    rtol = 1e-6 if settings.oit == "weighted" else 0.0
    for count in COUNTS:
        rng = np.random.default_rng(count + 7)
        fr = _fragments(count, rng)
        tri = jnp.asarray(np.where(np.arange(N) < count, rng.choice([2, 4, 6], N), 0), jnp.int32)
        # The last live entry in front: a prefix one entry short would drop a layer.
        front = fr.valid & jnp.asarray((rng.random(N) < 0.8) | (np.arange(N) == count - 1))
        values = jnp.asarray(rng.random((N, 5)), jnp.float32)
        background = jnp.asarray(rng.random((N_PIX, 3)), jnp.float32)
        whole = Layers(fr.pixel, tri, fr.depth, front, values)
        want_image, want_counts = whole_list(whole, background)
        got_image, got_counts = on_prefix(whole._replace(live=jnp.int32(count)), background)
        np.testing.assert_allclose(np.asarray(got_image), np.asarray(want_image), rtol=rtol,
                                   atol=0, err_msg=f"image, count {count}, {settings}")
        for k, v in want_counts.items():
            np.testing.assert_array_equal(np.asarray(got_counts[k]), np.asarray(v),
                                          err_msg=f"{k}, count {count}, {settings}")
        assert int(want_counts["transparent_fragments"]) == int(np.asarray(front).sum())


@pytest.mark.parametrize("settings", [BlendSettings(), BlendSettings(order="submission")],
                         ids=["sorted", "submission"])
def test_no_layer_in_front_leaves_the_background_bit_for_bit(settings):
    """The sorted blend's first pass runs unconditionally (one host read fewer a frame): over
    a list with no fragment in front of the opaque depth it must blend nothing, and count no
    pass."""
    scene = layered_quads(THREE)
    blend = jax.jit(lambda layers, bg: composite(scene, layers, bg, settings))
    for count in (0, 300):
        rng = np.random.default_rng(count + 11)
        fr = _fragments(count, rng)
        tri = jnp.asarray(np.where(np.arange(N) < count, 2, 0), jnp.int32)
        layers = Layers(fr.pixel, tri, fr.depth, jnp.zeros((N,), bool),
                        jnp.asarray(rng.random((N, 5)), jnp.float32), jnp.int32(count))
        background = jnp.asarray(rng.random((N_PIX, 3)), jnp.float32)
        image, counts = blend(layers, background)
        np.testing.assert_array_equal(np.asarray(image), np.asarray(background),
                                      err_msg=f"{count} fragments, none in front, {settings}")
        assert int(counts["transparent_passes"]) == 0, (count, settings)
        assert int(counts["transparent_fragments"]) == 0, (count, settings)


@pytest.mark.parametrize("params", [{"transparent_layers": 2}, {"oit": "weighted"}],
                         ids=["sorted", "weighted"])
def test_the_one_launch_pass_is_the_chunked_pass(params):
    """``blend_on_prefix`` (the test, the layer shader and the composite in one launch over the
    filled prefix; compacted in chunks below the shortest prefix) against the chunked pass
    (``front_work``, ``shade_layers``, ``composite``) on random lists of the three-quad scene's
    transparent triangles, their counts on both sides of the prefix lengths: the same image and
    counts; lanes hand-worked (the shortest prefix, 150 entries: one 150-lane chunk, or none
    with nothing in front; past it, the prefix length that holds the list)."""
    scene = layered_quads(THREE)
    cfg = make_config("deferred", width=8, height=8, **params)  # N_PIX pixels
    clip = clip_vertices(scene, scene.camera, cfg)

    def chunked(fr, opaque, background):
        front, work = front_work(fr, opaque, N_PIX)

        def points_of(items):
            return points_at(scene, scene.camera, clip, cfg, fr.tri[items], fr.pixel[items])

        layers, work = shade_layers(scene, scene.camera, fr, front, work, points_of, 64)
        image, counts = composite(scene, layers, background, settings_of(cfg))
        return image, dict(counts, transparent_invocations=work.invocations)

    one = jax.jit(lambda fr, opaque, bg: blend_on_prefix(scene, scene.camera, clip, fr, bg,
                                                         opaque, cfg))
    chunked = jax.jit(chunked)
    for count in COUNTS:
        rng = np.random.default_rng(count + 23)
        fr = dataclasses.replace(_fragments(count, rng), tri=jnp.asarray(
            np.where(np.arange(N) < count, rng.choice([2, 4, 6], N), 0), jnp.int32))
        opaque = jnp.asarray(rng.random(N_PIX), jnp.float32)
        background = jnp.asarray(rng.random((N_PIX, 3)), jnp.float32)
        want_image, want_counts = chunked(fr, opaque, background)
        got_image, got_counts, lanes = one(fr, opaque, background)
        np.testing.assert_allclose(np.asarray(got_image), np.asarray(want_image), rtol=1e-6,
                                   atol=1e-7, err_msg=f"image, count {count}, {params}")
        for k, v in want_counts.items():
            np.testing.assert_array_equal(np.asarray(got_counts[k]), np.asarray(v),
                                          err_msg=f"{k}, count {count}, {params}")
        shaded = int(want_counts["transparent_invocations"])
        assert (shaded > 0) == (count > 0), (count, shaded)
        want_lanes = (150 * (shaded > 0) if count <= 150
                      else min(m for m in prefix_sizes(N) if m >= count))
        assert int(lanes) == want_lanes, (count, shaded, int(lanes), params)
