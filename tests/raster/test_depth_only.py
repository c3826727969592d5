"""``rasterize_depth_clip`` is ``rasterize_clip`` without barycentrics: the same ids, depth and
counts, bit for bit; and ``Counts`` reads like the dict it replaces."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender.raster import rasterize_clip, rasterize_depth_clip, samples
from jaxrender.types import Counts, DepthBuffer
from tests.raster.conftest import gl_clip, pad
from tests.raster.test_exact import H, W, _random_scene


def _clipped_scene(rng):  # near-plane crossings: clipped fans
    p = rng.uniform(-3, 3, (300, 3))
    p[:, 2] = rng.uniform(-6, 1, 300)
    return pad(gl_clip(p, aspect=W / H), np.arange(300).reshape(-1, 3).astype(np.int32))


@pytest.mark.parametrize("kind", ["mixed_sizes", "clipped_msaa"])
def test_depth_only_equals_visbuffer(rng, kind):
    if kind == "clipped_msaa":
        (clip, faces), offsets = _clipped_scene(rng), samples.msaa(4)
    else:
        (clip, faces), offsets = _random_scene(rng, kind), None
    vis = rasterize_clip(clip, faces, W, H, sample_offsets=offsets)
    dep = rasterize_depth_clip(clip, faces, W, H, sample_offsets=offsets)
    assert isinstance(dep, DepthBuffer)
    for name in ("tri_id", "depth"):
        np.testing.assert_array_equal(np.asarray(getattr(dep, name)),
                                      np.asarray(getattr(vis, name)), err_msg=f"{kind}: {name}")
    assert dict((k, int(v)) for k, v in dep.counts.items()) == \
        dict((k, int(v)) for k, v in vis.counts.items()), kind
    assert int(vis.counts["fragments"]) > 0 and int(vis.counts["work_items"]) > 0
    if kind == "clipped_msaa":
        assert int(vis.counts["clipped"]) > 0


def test_counts_read_like_a_dict():
    d = {"a": 3, "b": 7, "c": -1}
    c = Counts.pack(d)
    assert list(c) == ["a", "b", "c"] and len(c) == 3
    assert {k: int(v) for k, v in c.items()} == d
    assert {k: int(v) for k, v in dict(c, e=jnp.int32(5)).items()} == dict(d, e=5)
    with pytest.raises(KeyError):
        c["missing"]
    # A pytree with one leaf: through jit and vmap, names kept.
    leaves = jax.tree_util.tree_leaves(c)
    assert len(leaves) == 1 and leaves[0].dtype == jnp.int32
    doubled = jax.jit(lambda x: Counts(x.names, x.values * 2))(c)
    assert {k: int(v) for k, v in doubled.items()} == {k: 2 * v for k, v in d.items()}
    batched = jax.vmap(lambda s: Counts.pack({"a": s, "b": s + 1}))(jnp.arange(4))
    np.testing.assert_array_equal(np.asarray(batched["b"]), np.arange(4) + 1,
                                  err_msg="vmapped counts: one value per batch element")
