"""The top-level API takes a study entry's parameters as a study does: ``shader_cost`` sets the
scene's extra light layers, equal to loading the scene with that effect."""

import numpy as np
import pytest

import jaxrender


def test_shader_cost_in_render_equals_the_scene_effect():
    scene = jaxrender.load_scene("spheres", rows=1, cols=1)
    costly = jaxrender.load_scene("spheres", rows=1, cols=1, effects={"shader_cost": 2})
    camera = jaxrender.default_camera(scene)
    got = jaxrender.render(scene, camera, "deferred", width=16, height=9, shader_cost=2)
    want = jaxrender.render(costly, camera, "deferred", width=16, height=9)
    plain = jaxrender.render(scene, camera, "deferred", width=16, height=9)
    np.testing.assert_array_equal(np.asarray(got.image), np.asarray(want.image),
                                  err_msg="render(shader_cost=2) vs a scene with shader_cost 2")
    assert not np.array_equal(np.asarray(got.image), np.asarray(plain.image)), \
        "the layers should change the image a little"
    with pytest.raises(KeyError, match="no parameter 'shader_costs'"):
        jaxrender.render(scene, camera, "deferred", width=16, height=9, shader_costs=2)
