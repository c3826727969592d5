"""Scene TOML files and mesh files: valid ones load, malformed ones name the file and the key."""

import numpy as np
import pytest
import trimesh

from jaxrender.scene import SceneConfigError, load_scene
from jaxrender.scene.loader import CONFIG_DIR

GOOD = """
name = "t"
[camera]
eye = [0, 1, 3]
target = [0, 0, 0]
[[materials]]
name = "a"
albedo = [0.5, 0.5, 0.5]
[[meshes]]
primitive = "plane"
size = [2, 2]
material = "a"
[[lights]]
type = "directional"
direction = [0, 1, 0]
irradiance = 1.0
"""


def _write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_bundled_scene_files_load():
    files = sorted(CONFIG_DIR.glob("*.toml"))
    assert files, f"no scene files in {CONFIG_DIR}"
    for f in files:
        s = load_scene(f)
        assert s.num_triangles > 0 and np.all(np.isfinite(np.asarray(s.positions))), f
    s = load_scene("courtyard")
    assert s.effects.shadows and s.effects.procedural and s.effects.specular
    assert s.lights.point_position.shape == (1, 3)


def test_minimal_file_and_effect_override(tmp_path):
    s = load_scene(_write(tmp_path, GOOD + "[effects]\nshader_cost = 2\n"))
    assert s.name == "t" and s.num_triangles == 2 and s.effects.shader_cost == 2
    assert load_scene(_write(tmp_path, GOOD), effects={"specular": True}).effects.specular


@pytest.mark.parametrize("edit, key", [
    (("[[meshes]]\nprimitive", "[[meshes]]\nprimitiv"), "meshes[0].primitiv"),
    (('albedo = [0.5, 0.5, 0.5]', 'albedo = "red"'), "materials[0].albedo"),
    (('albedo = [0.5, 0.5, 0.5]', 'albedo = [0.5, 0.5]'), "materials[0].albedo"),
    (('material = "a"', 'material = "b"'), "meshes[0].material"),
    (('primitive = "plane"', 'file = "missing.obj"'), "meshes[0].file"),
    (('name = "a"', 'name = "a"\ntexture = "nope.png"'), "materials[0].texture"),
    (('irradiance = 1.0', 'irradiance = 1.0\nposition = [0, 0, 0]'), "lights[0].position"),
    (('type = "directional"', 'type = "spot"'), "lights[0].type"),
    (('eye = [0, 1, 3]\n', ''), "camera.eye"),
    (('name = "t"', 'name = "t"\nfoo = 1'), "foo"),
    (('[camera]', '[effects]\nshadowz = true\n[camera]'), "effects.shadowz"),
    (('[camera]', '[effects]\nshader_cost = "many"\n[camera]'), "effects.shader_cost"),
])
def test_malformed_files_name_file_and_key(tmp_path, edit, key):
    old, new = edit
    assert old in GOOD
    path = _write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(SceneConfigError) as err:
        load_scene(path)
    assert err.value.key == key, str(err.value)
    assert str(path) in str(err.value) and repr(key) in str(err.value)


def test_bad_syntax_names_the_file(tmp_path):
    path = _write(tmp_path, "name = [")
    with pytest.raises(SceneConfigError, match="scene.toml"):
        load_scene(path)


def _textured_quad():
    from PIL import Image

    m = trimesh.Trimesh(vertices=[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
                        faces=[[0, 1, 2], [0, 2, 3]], process=False)
    img = Image.fromarray(np.full((8, 8, 4), [255, 0, 0, 255], np.uint8))
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    m.visual = trimesh.visual.TextureVisuals(uv=uv, image=img)
    return m


@pytest.mark.parametrize("suffix", ["obj", "ply", "glb"])
def test_mesh_files_load_with_uvs_and_textures(tmp_path, suffix):
    mesh = _textured_quad()
    path = tmp_path / f"quad.{suffix}"
    mesh.export(path)
    toml = GOOD.replace('primitive = "plane"\nsize = [2, 2]\nmaterial = "a"',
                        f'file = "quad.{suffix}"\ntranslate = [1, 0, 0]\nscale = 2.0')
    for s in (load_scene(_write(tmp_path, toml)), load_scene(path)):
        assert s.num_triangles == 2, suffix
        pos = np.asarray(s.positions)
        assert np.all(np.isfinite(np.asarray(s.normals)))
    s = load_scene(_write(tmp_path, toml))
    np.testing.assert_allclose(np.asarray(s.bounds), [[1, 0, 0], [3, 2, 0]], atol=1e-6,
                               err_msg=f"{suffix}: transform applied")
    if suffix in ("obj", "glb"):  # PLY keeps no texture image
        assert s.effects.textures, f"{suffix}: base-colour texture lost"
        uvs = np.asarray(s.uvs)
        assert uvs.max() > 0.9 and uvs.min() < 0.1, f"{suffix}: uvs lost"
        red = np.asarray(s.textures.atlas)[0, 0, 0, :3]
        assert red[0] > 0.9 and red[1] < 0.05, f"{suffix}: texture colour {red}"
    del pos
