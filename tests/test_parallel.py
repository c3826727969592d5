"""jaxrender.parallel: sharded batches equal the unsharded results, on 1 device and on 2
(a subprocess with XLA_FLAGS=--xla_force_host_platform_device_count=2)."""

import json
import os
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrender import parallel
from jaxrender.raster import rasterize
from jaxrender.scene.mesh import closed_uv_sphere
from jaxrender.scene.camera_path import frame, orbit

W, H = 24, 16
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _scene():
    v, f = closed_uv_sphere(6, 10)
    return jnp.asarray(v), jnp.asarray(f)


def _ids(scene, camera, cfg):
    """A stand-in pipeline: the rasterizer's triangle ids (no shading, cheap to compile)."""
    positions, faces = scene
    width, height = cfg
    return rasterize(positions, faces, camera, width, height).tri_id


def _project(point, scale):
    return jnp.sin(point * scale) + jnp.sum(point)


def test_mesh_covers_every_device():
    mesh = parallel.device_mesh()
    assert mesh.size == jax.device_count()
    assert mesh.axis_names == (parallel.AXIS,)


def test_pad_repeats_the_last_item():
    x = {"a": jnp.arange(5.0), "b": jnp.arange(10.0).reshape(5, 2)}
    padded, n = parallel.pad_batch(x, 4)
    assert n == 5 and padded["a"].shape == (8,) and padded["b"].shape == (8, 2)
    np.testing.assert_array_equal(np.asarray(padded["a"][5:]), [4.0, 4.0, 4.0])
    with pytest.raises(ValueError, match="leading axis"):
        parallel.pad_batch({"a": jnp.zeros(3), "b": jnp.zeros(4)}, 2)


@pytest.mark.parametrize("chunk", [0, 2])
def test_sharded_map_equals_vmap(chunk):
    pts = jnp.arange(15.0, dtype=jnp.float32).reshape(5, 3)
    scale = jnp.float32(0.5)
    got = parallel.sharded_map(_project, pts, scale, chunk=chunk)
    want = jax.vmap(_project, in_axes=(0, None))(pts, scale)
    np.testing.assert_array_equal(np.asarray(got), np.asarray(want))


def test_render_frames_equals_frame_by_frame():
    scene = _scene()
    path = orbit((0.0, 0.0, 0.0), 3.0, 3, 25.0, height=1.0)
    got = np.asarray(parallel.render_frames(_ids, scene, path.cameras, (W, H)))
    assert got.shape == (3, H, W)
    for t in range(3):
        np.testing.assert_array_equal(got[t], np.asarray(_ids(scene, frame(path.cameras, t), (W, H))),
                                      err_msg=f"frame {t}")
    assert (got >= 0).any()


def test_round_robin_matches_direct_calls():
    f = jax.jit(lambda x: x * 2.0)
    outs = parallel.round_robin([(f, (jnp.float32(i),)) for i in range(3)])
    assert [float(o) for o in outs] == [0.0, 2.0, 4.0]


_TWO_DEVICES = textwrap.dedent("""
    import json, jax, numpy as np, jax.numpy as jnp
    from jaxrender import parallel
    from jaxrender.scene.camera_path import frame, orbit
    import tests.test_parallel as tp
    assert jax.device_count() == 2, jax.devices()
    scene = tp._scene()
    path = orbit((0.0, 0.0, 0.0), 3.0, 3, 25.0, height=1.0)   # 3 frames: padded to 4
    out = parallel.render_frames(tp._ids, scene, path.cameras, (tp.W, tp.H))
    got = np.asarray(out)
    frames_equal = [bool(np.array_equal(got[t], np.asarray(
        tp._ids(scene, frame(path.cameras, t), (tp.W, tp.H))))) for t in range(3)]
    pts = jnp.arange(21.0, dtype=jnp.float32).reshape(7, 3)
    m = parallel.sharded_map(tp._project, pts, jnp.float32(0.5), chunk=1)
    want = jax.vmap(tp._project, in_axes=(0, None))(pts, jnp.float32(0.5))
    prog = parallel._vmapped(tp._project, 1, parallel.device_mesh())
    xs, _ = parallel.shard_batch(pts, parallel.device_mesh())
    spread = len(prog(xs, jnp.float32(0.5)).sharding.device_set)
    rr = parallel.round_robin([(jax.jit(lambda x: x + 1.0), (jnp.float32(i),)) for i in range(2)])
    print(json.dumps({"frames_equal": frames_equal, "shape": list(got.shape),
                      "map_equal": bool(np.array_equal(np.asarray(m), np.asarray(want))),
                      "spread": spread, "rr": [float(x) for x in rr],
                      "rr_devices": sorted(d.id for o in rr for d in o.devices())}))
""")


@pytest.mark.slow
def test_two_devices_equal_unsharded():
    env = dict(os.environ, JAX_PLATFORMS="cpu",
               XLA_FLAGS=(os.environ.get("XLA_FLAGS", "")
                          + " --xla_force_host_platform_device_count=2").strip(),
               PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    p = subprocess.run([sys.executable, "-c", _TWO_DEVICES], check=False, cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    r = json.loads(p.stdout.strip().splitlines()[-1])
    assert r["shape"] == [3, H, W]
    assert r["frames_equal"] == [True, True, True]
    assert r["map_equal"] and r["spread"] == 2
    assert r["rr"] == [1.0, 2.0] and r["rr_devices"] == [0, 1]
