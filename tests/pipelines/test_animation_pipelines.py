"""The animation clock through the one program every pipeline runs in: each step sees the scene
posed at its frame t, a frame rendered alone at t equals frame t of a sequence, and a static
scene's program holds no pose."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines import get_pipeline, make_config, program, registry
from jaxrender.scene.animation import pose
from jaxrender.scene.camera_path import frame as camera_at
from jaxrender.scene.camera_path import pan
from jaxrender.shading import load_lit_scene
from jaxrender.types import Frame

W, H = 16, 12
FRAMES = 3


def _scene():
    return load_lit_scene("spheres_spin", rows=1, cols=2, lat=6, lon=12, spin_deg_per_s=600.0)


def _probe(scene, camera, cfg):
    """test: what a step sees of the scene"""
    return Frame(jnp.zeros((cfg.height, cfg.width, 3)), {}, {"positions": scene.positions})


PROBE = registry.Pipeline("probe", registry.RenderConfig, registry.FrameStep(_probe))


def test_each_step_sees_the_scene_posed_at_its_frame():
    scene = _scene()
    path = pan(scene.camera, FRAMES, 1.0, H)
    cfg = registry.RenderConfig(width=W, height=H)
    seq = PROBE.render_sequence(scene, path, cfg)
    for t in range(FRAMES):
        want = np.asarray(pose(scene, t).positions)
        np.testing.assert_array_equal(np.asarray(seq.aux["positions"][t]), want,
                                      err_msg=f"sequence frame {t} is not the pose at {t}")
        alone = PROBE.render(scene, camera_at(path.cameras, t), cfg, t=t)
        np.testing.assert_array_equal(np.asarray(alone.aux["positions"]), want,
                                      err_msg=f"frame {t} rendered alone is not the pose at {t}")
    assert np.abs(np.asarray(seq.aux["positions"][2] - seq.aux["positions"][0])).max() > 0.05


def test_a_pipeline_frame_alone_at_t_equals_frame_t_of_its_sequence():
    scene = _scene()
    path = pan(scene.camera, FRAMES, 1.0, H)
    pipe = get_pipeline("deferred")
    cfg = make_config("deferred", width=W, height=H)
    seq = pipe.render_sequence(scene, path, cfg)
    t = FRAMES - 1
    alone = pipe.render(scene, camera_at(path.cameras, t), cfg, t=t)
    np.testing.assert_allclose(np.asarray(alone.image), np.asarray(seq.image[t]), atol=1e-6,
                               err_msg="deferred: frame t alone != frame t of the sequence")
    assert np.abs(np.asarray(seq.image[t]) - np.asarray(seq.image[0])).max() > 1e-2, \
        "the spheres should have visibly turned between the first and the last frame"


def test_a_still_scene_compiles_no_pose():
    scene = load_lit_scene("spheres", rows=1, cols=1, lat=4, lon=8)
    moving = load_lit_scene("spheres_spin", rows=1, cols=1, lat=4, lon=8)
    cfg = registry.RenderConfig(width=W, height=H)

    def hlo(sc):
        lowered, _ = program.lower(PROBE, sc, sc.camera, cfg)
        return lowered.as_text(debug_info=True)

    assert "/animation/" not in hlo(scene), "a still scene's program poses it"
    assert "/animation/" in hlo(moving), "the probe must see the moving scene's pose"
    # The frame index is traced: another t is the same program.
    before = program.cache_size()
    PROBE.render(moving, moving.camera, cfg, t=1)
    PROBE.render(moving, moving.camera, cfg, t=5)
    assert program.cache_size() == before + 1
    jax.block_until_ready(PROBE.render(moving, moving.camera, cfg, t=jnp.int32(7)).image)
    assert program.cache_size() == before + 1
