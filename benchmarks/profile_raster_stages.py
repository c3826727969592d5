"""Stage breakdown of the rasterizer on one scene, and alternatives for the owner lookup.

    python benchmarks/profile_raster_stages.py --tris 2600000 --size 1920x1080
"""

from __future__ import annotations

import argparse

import jax
import jax.numpy as jnp

from jaxrender.bench.raster import terrain_clip
from jaxrender.parsing import resolution_arg
from jaxrender.raster.resolve import resolve
from jaxrender.raster.setup import setup_triangles
from jaxrender.raster.work_items import EMPTY_KEY, chunk_items, depth_key
from jaxrender.timing import environment, time_compiled


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--tris", type=int, default=2_600_000)
    ap.add_argument("--size", type=resolution_arg, default="1920x1080")
    ap.add_argument("--capacity", type=int, default=1 << 22)
    a = ap.parse_args(argv)
    w, h = a.size
    clip, faces = terrain_clip(a.tris, w, h)
    n = faces.shape[0]
    cap = a.capacity
    print(environment(), "tris", n, "size", f"{w}x{h}", "capacity", cap)
    with jax.enable_x64(True):
        off = jnp.asarray([128, 128], jnp.int64)
        ones, ids = jnp.ones((n,), bool), jnp.arange(n, dtype=jnp.int32)

        def t(name, f, *args):
            r = time_compiled(jax.jit(f), *args, repeats=20)
            print(f"{name:40s} {r['median_ms']:8.3f} ms")
            return r["out"]

        t("gather clip[faces]", lambda c, f: c[f], clip, faces)
        s = t("setup", lambda c, f: setup_triangles(c[f], ones, ids, w, h, off, False), clip, faces)
        incl = t("cumsum counts", lambda s: jnp.cumsum(s.count), s)
        t("owner: scatter marks + assoc scan", lambda s, i: chunk_items(s, i, jnp.int64(0), cap, off).slot, s, incl)

        def cummax_owner(s, incl):
            starts = incl - s.count
            m = jnp.full((cap,), -1, jnp.int32).at[jnp.where(s.count > 0, starts, cap)].max(ids, mode="drop")
            return jax.lax.cummax(m)

        t("owner: scatter marks + lax.cummax", cummax_owner, s, incl)
        t("owner: searchsorted scan", lambda i: jnp.searchsorted(i, jnp.arange(cap, dtype=jnp.int64), side="right"), incl)
        ch = t("chunk (all outputs)", lambda s, i: chunk_items(s, i, jnp.int64(0), cap, off), s, incl)

        def scat(ch):
            pix = jnp.where(ch.covered, ch.py * w + ch.px, w * h)
            z = jnp.full((w * h,), EMPTY_KEY, jnp.int64)
            return z.at[pix].min(depth_key(ch.depth, ch.tri), mode="drop")

        zb = t("scatter-min keys", scat, ch)
        t("resolve", lambda z: resolve(z, clip, faces, w, h, jnp.asarray([0.5, 0.5], jnp.float32)), zb)


if __name__ == "__main__":
    main()
