"""Transparent materials: opacity and blend modes validated, the transparency effect derived
from the materials, and scene files' bad input refused with file and key named."""

import numpy as np
import pytest

from jaxrender.scene import SceneConfigError, load_scene
from jaxrender.scene.materials import Material, pack_materials
from tests.pipelines.transparent_scenes import layered_quads

GLASS = """
name = "t"
[camera]
eye = [0, 1, 3]
target = [0, 0, 0]
[[materials]]
name = "a"
albedo = [0.5, 0.5, 0.5]
{extra}
[[meshes]]
primitive = "plane"
size = [2, 2]
material = "a"
"""


def _write(tmp_path, extra):
    p = tmp_path / "scene.toml"
    p.write_text(GLASS.format(extra=extra))
    return p


def _image(tmp_path, name, channels):
    import imageio.v3 as iio

    img = np.full((4, 4, channels), 128, np.uint8)
    iio.imwrite(tmp_path / name, img)
    return name


def test_material_packing_and_the_derived_effect():
    mats = [Material("o"), Material("g", blend="over", opacity=0.25),
            Material("p", blend="additive", opacity=1.0)]
    packed = pack_materials(mats)
    np.testing.assert_array_equal(np.asarray(packed.blend), [0, 1, 2])
    np.testing.assert_allclose(np.asarray(packed.opacity), [1.0, 0.25, 1.0])
    assert layered_quads([((1, 0, 0), 0.5, "over", 0.0)]).effects.transparency
    assert not layered_quads([]).effects.transparency


@pytest.mark.parametrize("kwargs, problem", [
    ({"blend": "over", "opacity": 1.5}, "opacity must be in"),
    ({"blend": "over", "opacity": -0.1}, "opacity must be in"),
    ({"blend": "multiply"}, "blend 'multiply' not in"),
    ({"opacity": 0.5}, "no effect with blend"),
    ({"blend": "over", "opacity_source": "texture_alpha"}, "needs a texture"),
    ({"blend": "over", "opacity_source": "vertex"}, "opacity_source 'vertex' not in"),
    ({"blend": "over", "alpha_tested": True}, "cannot also be alpha_tested"),
])
def test_bad_materials_are_refused(kwargs, problem):
    with pytest.raises(ValueError, match=problem):
        Material("m", **kwargs)


@pytest.mark.parametrize("extra, key", [
    ('blend = "over"\nopacity = 1.2', "materials[0].opacity"),
    ('blend = "glow"', "materials[0].blend"),
    ('opacity = 0.5', "materials[0].opacity"),
    ('blend = "over"\nopacity_source = "texture_alpha"', "materials[0].opacity_source"),
])
def test_scene_files_name_the_key(tmp_path, extra, key):
    path = _write(tmp_path, extra)
    with pytest.raises(SceneConfigError) as e:
        load_scene(path)
    assert e.value.key == key and str(path) in str(e.value), str(e.value)


def test_a_texture_without_alpha_asked_for_alpha_is_refused(tmp_path):
    rgb, rgba = _image(tmp_path, "rgb.png", 3), _image(tmp_path, "rgba.png", 4)
    ask = 'blend = "over"\nopacity_source = "texture_alpha"\ntexture = "{}"'
    with pytest.raises(SceneConfigError, match="no alpha channel") as e:
        load_scene(_write(tmp_path, ask.format(rgb)))
    assert e.value.key == "materials[0].opacity_source"
    scene = load_scene(_write(tmp_path, ask.format(rgba)))  # alpha 128/255: accepted
    assert scene.effects.transparency and bool(scene.materials.opacity_texture[0])


def test_the_transparency_flag_follows_the_materials(tmp_path):
    with pytest.raises(SceneConfigError, match="transparency"):
        load_scene(_write(tmp_path, "[effects]\ntransparency = true"))
    scene = load_scene(_write(tmp_path, 'blend = "additive"\nopacity = 0.3'))
    assert scene.effects.transparency


ONTO = """
base = "{base}"
[[materials]]
name = "glass"
albedo = [0.6, 0.8, 1.0]
blend = "over"
opacity = 0.4
[[meshes]]
primitive = "plane"
size = [3, 2]
material = "glass"
rotate_deg = [90, 0, 0]
translate = [0, 0.5, 1.0]
"""


def test_a_scene_file_adds_transparent_objects_to_a_builtin_scene(tmp_path):
    p = tmp_path / "onto.toml"
    p.write_text(ONTO.format(base="room"))
    scene, base = load_scene(p), load_scene("room")
    v, t, m = base.num_vertices, base.num_triangles, base.materials.count
    assert scene.num_triangles == t + 2 and scene.materials.count == m + 1
    assert scene.effects.transparency and scene.effects.shadows and scene.effects.normal_map
    np.testing.assert_array_equal(np.asarray(scene.positions[:v]), np.asarray(base.positions))
    np.testing.assert_array_equal(np.asarray(scene.faces[t:]) >= v, True)
    np.testing.assert_array_equal(np.asarray(scene.tri_material[t:]), m)
    assert int(scene.materials.blend[m]) == 1
    assert float(scene.materials.opacity[m]) == np.float32(0.4)
    assert int(scene.tri_object[t]) == int(base.tri_object.max()) + 1
    p.write_text(ONTO.format(base="nowhere"))
    with pytest.raises(SceneConfigError) as e:
        load_scene(p)
    assert e.value.key == "base"
    p.write_text(ONTO.format(base="room") + '[[lights]]\ntype = "ambient"\nradiance = 1\n')
    with pytest.raises(SceneConfigError) as e:
        load_scene(p)
    assert e.value.key == "lights"
    p.write_text(ONTO.format(base="spheres_spin"))
    with pytest.raises(SceneConfigError, match="still scene only"):
        load_scene(p)
