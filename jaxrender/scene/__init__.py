"""What is rendered: meshes, built-in scenes, cameras and camera paths, lights, materials,
effect flags."""

from jaxrender.scene.builtin import list_builtin_scenes
from jaxrender.scene.camera import Camera, look_at, world_to_clip, world_to_view
from jaxrender.scene.config import SceneConfigError
from jaxrender.scene.effects import BLINN_PHONG, GGX, LAMBERT, PROC_NONE, PROC_STRIPES, Effects
from jaxrender.scene.lights import Lights, make_lights
from jaxrender.scene.loader import load_scene
from jaxrender.scene.materials import Material, Materials
from jaxrender.scene.mesh import MeshPart
from jaxrender.scene.scene import (Scene, ShadowMap, advance, build_scene, default_camera,
                                   with_effects)
from jaxrender.scene.textures import Textures

__all__ = [
    "BLINN_PHONG", "GGX", "LAMBERT", "PROC_NONE", "PROC_STRIPES", "Camera", "Effects", "Lights",
    "Material", "Materials", "MeshPart", "Scene", "SceneConfigError", "ShadowMap", "Textures",
    "advance", "build_scene", "default_camera", "list_builtin_scenes", "load_scene", "look_at",
    "make_lights", "with_effects", "world_to_clip", "world_to_view",
]
