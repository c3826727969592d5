"""shader_cost in a study file: every pipeline entry takes it in params or sweep, it reaches
the variants (and not the pipeline's config), and its mistakes name the file and the key."""

import pytest

from jaxrender.errors import StudyError, UserError
from jaxrender.study import backend, shader_cost
from jaxrender.study.schema import load_study

from tests.study.doubles import MINIMAL_STUDY as BASE
from tests.study.doubles import write_study as _write


def test_sweep_reaches_the_variants(fake):
    s = load_study(_write(fake, BASE + """
        params = { levels = 4 }
        sweep = { shader_cost = [0, 4, 16] }
        [[pipelines]]
        type = "flat"
        label = "fixed"
        params = { shader_cost = 2 }
        """))
    got = [(v.label, dict(v.params)) for v in s.variants]
    assert got == [("flat", {"levels": 4, "shader_cost": 0}),
                   ("flat", {"levels": 4, "shader_cost": 4}),
                   ("flat", {"levels": 4, "shader_cost": 16}),
                   ("fixed", {"shader_cost": 2})]
    assert shader_cost.split({"levels": 4, "shader_cost": 16}) == ({"levels": 4}, 16)
    assert shader_cost.split({"levels": 4}) == ({"levels": 4}, None)


@pytest.mark.parametrize("text, key, msg", [
    ('sweep = { shader_cost = [0, -1] }', "pipelines[0].sweep.shader_cost", ">= 0"),
    ('params = { shader_cost = "many" }', "pipelines[0].params.shader_cost", "integer"),
    ('params = { shader_cost = 1.5 }', "pipelines[0].params.shader_cost", "integer"),
    ('params = { shader_cost = 1 }\nsweep = { shader_cost = [2] }',
     "pipelines[0].sweep.shader_cost", "both a fixed parameter and swept"),
    ('[reference]\nparams = { shader_cost = 4 }', "reference.params.shader_cost",
     "scene's own shader"),
])
def test_mistakes_name_the_key(fake, text, key, msg):
    with pytest.raises(StudyError) as e:
        load_study(_write(fake, BASE + text + "\n"))
    assert e.value.path == key and msg in str(e.value), str(e.value)


def test_scene_cost_set_and_refused_without_effects(fake):
    scene = backend.load_scene("tiny", {})  # the fake scene: no shader effects
    assert backend.shader_cost(scene) is None
    assert backend.with_shader_cost(scene, None) is scene
    with pytest.raises(UserError, match="no shader effects"):
        backend.with_shader_cost(scene, 4)
