"""The shader-cost layers' time per layer evaluation by launch size: is a unit of work the
same wherever it runs?

    python benchmarks/bench_cost_layers.py --scenes foliage room --sizes 4096 65536 0
    PYTHONPATH=.v/layer_groups python benchmarks/bench_cost_layers.py --label groups  # a variant
    python benchmarks/bench_cost_layers.py --layers-minor  # the layers summed along lanes' rows
    python benchmarks/bench_cost_layers.py --layers-grouped  # in groups, partial sums stored
    python benchmarks/bench_cost_layers.py --layers-stored  # small launches: layers stored, summed

Rasterizes each scene's default view, compacts its covered pixels, and times one launch of
``surface_points`` and ``shade()`` over the first n of them (0: all) at shader cost 0 and at
``--cost``. The slope is (t_cost - t_0) / (n x cost): picoseconds per layer evaluation. If the
GPU is not filled (a few thousand lanes) or the layers' intermediates spill from the cache, a
pipeline's slope depends on its launch sizes rather than its work.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.pipelines import make_config
from jaxrender.pipelines.visibility import visibility
from jaxrender.scene import default_camera
from jaxrender.shading import load_lit_scene, shade, surface_points
from jaxrender.study.backend import with_shader_cost
from jaxrender.timing import device_description, time_call

PACKAGE_LAYER_SUM = sys.modules["jaxrender.shading.shade"].layer_sum


def covered_points(scene, camera, w, h):
    """(tri_id, bary, dbary_dx, dbary_dy) of the covered pixels, compacted, as NumPy."""
    cfg = make_config("deferred", width=w, height=h)
    vis = jax.jit(lambda s, c: visibility(s, c, cfg))(scene, camera)
    flat = lambda a: np.asarray(a).reshape((w * h,) + np.shape(a)[2:])  # noqa: E731
    tri = flat(vis.tri_id)
    keep = np.flatnonzero(tri >= 0)
    return tuple(flat(a)[keep] for a in (vis.tri_id, vis.bary, vis.dbary_dx, vis.dbary_dy))


def layer_sum_minor(layer, angles, lanes: int):
    """``shade.layer_sum`` with the layers as the minor axis ([lanes, layers], summed along each
    lane's row) and every layer in one batch: a variant for this bench. Summed over the major
    axis ([layers, lanes]), XLA reduces columns, which a launch of a few thousand lanes may not
    spread over the GPU; a row reduction was to give each lane threads of its own (RESULTS.md,
    twenty-eighth session: it did not change such launches)."""
    out = jax.vmap(layer, out_axes=-1)(angles)
    return jax.tree.map(lambda x: jnp.sum(x, axis=-1), out)


def layer_sum_grouped(layer, angles, lanes: int, fill: int = 1 << 18):
    """``shade.layer_sum`` in groups, every layer in one batch: a variant for this bench. The
    layers are cut into groups (groups x lanes at most ``fill``, the threads an H100 holds) of
    ``n_layers // groups`` layers, each group summed over its layers, the partial sums stored
    (``fusion.materialize``: XLA may otherwise merge the two sums into one reduction, whose
    threads are the lanes alone), then summed over the groups; the layers left over are
    summed after them. (Shader cost c is c + 1 layers, often a prime: 257 at cost 256.)"""
    from jaxrender.fusion import materialize

    n_layers = angles.shape[0]
    groups = max(1, min(fill // max(int(lanes), 1), n_layers))

    def batch(some):
        return jax.tree.map(lambda x: jnp.sum(x, axis=0), jax.vmap(layer)(some))

    if groups == 1:
        return batch(angles)
    size = n_layers // groups
    parts = jax.vmap(batch)(angles[:groups * size].reshape(groups, size))
    total = jax.tree.map(lambda x: jnp.sum(materialize(x), axis=0), parts)
    if groups * size < n_layers:
        total = jax.tree.map(jnp.add, total, batch(angles[groups * size:]))
    return total


STORED_LANES = 1 << 16
STORED_EVALUATIONS = 1 << 25  # layers x lanes at most: 200 MB of stored values for 3 channels


def layer_sum_stored(layer, angles, lanes: int, most: int = STORED_EVALUATIONS):
    """``shade.layer_sum`` for a launch of at most STORED_LANES lanes and ``most`` layer
    evaluations (benchmarks/variants/layers_stored.patch puts it in the package): every layer's
    value stored (``fusion.materialize_all``: the evaluations run as a scatter's updates, a
    thread each, over layers x lanes x 3 channels), then summed over the layers. XLA otherwise
    fuses the evaluations into the reduction over the layers, whose threads a launch of a few
    thousand lanes does not give the GPU enough of (RESULTS.md, twenty-eighth and twenty-ninth
    sessions: 4,096 lanes cost 9-12x the full screen a layer evaluation, in any axis order or
    grouping). Larger launches take the package's own. Not adopted: 1.6-3.6x slower a layer
    evaluation than the package's sum on an H200 (RESULTS.md, thirtieth session)."""
    from jaxrender.fusion import materialize_all

    if int(lanes) > STORED_LANES or angles.shape[0] * int(lanes) > most:
        return PACKAGE_LAYER_SUM(layer, angles, lanes)
    leaves, tree = jax.tree.flatten(jax.vmap(layer)(angles))
    return jax.tree.unflatten(tree, [jnp.sum(x, axis=0) for x in materialize_all(*leaves)])


def time_launch(scene, camera, pts, repeats: int) -> tuple[float, float]:
    """(median ms, compile s) of one launch shading ``pts``."""
    fn = jax.jit(lambda s, c, p: shade(surface_points(s, c, *p), s))
    t0 = time.perf_counter()
    call = fn.lower(scene, camera, pts).compile()
    compile_s = time.perf_counter() - t0
    _, median, _ = time_call(call, scene, camera, pts, repeats=repeats, warmup=2)
    return median, compile_s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["foliage", "room"])
    ap.add_argument("--sizes", nargs="+", type=int, default=[4096, 65536, 0],
                    help="lanes per launch; 0: every covered pixel")
    ap.add_argument("--cost", type=int, default=256)
    ap.add_argument("--resolution", type=resolution_arg, default="1920x1080")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--out", default="cost_layers.jsonl")
    ap.add_argument("--label", default="", help="a name for this tree in the rows")
    variant = ap.add_mutually_exclusive_group()
    variant.add_argument("--layers-minor", action="store_true",
                         help="time layer_sum_minor in place of shade.layer_sum")
    variant.add_argument("--layers-grouped", action="store_true",
                         help="time layer_sum_grouped in place of shade.layer_sum")
    variant.add_argument("--layers-stored", action="store_true",
                         help="time layer_sum_stored in place of shade.layer_sum")
    a = ap.parse_args(argv)
    # The package exports the function ``shade`` under the module's name.
    shade_module = sys.modules["jaxrender.shading.shade"]
    if a.layers_minor:
        shade_module.layer_sum = layer_sum_minor
    if a.layers_grouped:
        shade_module.layer_sum = layer_sum_grouped
    if a.layers_stored:
        shade_module.layer_sum = layer_sum_stored
    w, h = a.resolution
    print(f"device: {device_description()}, jax {jax.__version__}, {a.label}", flush=True)
    print("| scene | lanes | ms at 0 | ms at cost | ps per layer evaluation | compile s |")
    print("|---|---:|---:|---:|---:|---:|", flush=True)
    for name in a.scenes:
        base = load_lit_scene(name)
        camera = default_camera(base)
        pts_all = covered_points(base, camera, w, h)
        costly = with_shader_cost(base, a.cost)
        for n in a.sizes:
            pts = tuple(jnp.asarray(p[:n] if n else p) for p in pts_all)
            lanes = pts[0].shape[0]
            t_zero, _ = time_launch(base, camera, pts, a.repeats)
            t_cost, compile_s = time_launch(costly, camera, pts, a.repeats)
            ps = (t_cost - t_zero) * 1e9 / (lanes * a.cost)
            row = dict(scene=name, label=a.label, lanes=lanes, ms_zero=t_zero, ms_cost=t_cost,
                       cost=a.cost, ps_per_layer=ps, compile_s=compile_s)
            with open(a.out, "a") as f:
                f.write(json.dumps(row) + "\n")
            print(f"| {name} | {lanes} | {t_zero:.3f} | {t_cost:.3f} | {ps:.1f} | {compile_s:.1f} |",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
