"""``load_scene``: a built-in name, a scene TOML file (or the stem of one in configs/scenes/),
or a single mesh file."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jaxrender import catalog
from jaxrender.scene.builtin import BUILTINS, builtin_scene
from jaxrender.scene.camera import look_at
from jaxrender.scene.config import load_scene_toml
from jaxrender.scene.hard_cases import HARD_SCENES
from jaxrender.scene.lights import make_lights
from jaxrender.scene.mesh_io import load_mesh_file
from jaxrender.scene.scene import Scene, build_scene, with_effects

CONFIG_DIR = catalog.builtin_dir("scenes")
MESH_SUFFIXES = {".obj", ".ply", ".glb", ".gltf", ".stl", ".off"}


def load_scene(name_or_path: str | Path, *, effects: dict | None = None,
               **size_params) -> Scene:
    """Load a scene. ``effects`` overrides flags; ``size_params`` go to a built-in builder.

    Pure description: nothing is rendered here. A scene whose effects ask for shadows has no
    shadow map yet; ``jaxrender.shading.load_lit_scene`` loads it with one.
    """
    key = str(name_or_path)
    if key in BUILTINS or key in HARD_SCENES:
        build = builtin_scene if key in BUILTINS else (lambda k, **kw: HARD_SCENES[k](**kw))
        scene = build(key, **size_params)
        if effects:
            scene = with_effects(scene, **effects)
    else:
        if size_params:
            raise TypeError(f"load_scene({key!r}): size parameters {sorted(size_params)} apply to "
                            f"built-in scenes only ({', '.join(BUILTINS)})")
        path = Path(key)
        # A scene file's stem: the nearest local configs/scenes first, then the built-ins,
        # as a study file finds it.
        entry = None if path.exists() else catalog.find(
            "scenes", key, catalog.local_configs(Path.cwd()))
        if entry is not None:
            path = entry.path
        if path.suffix.lower() in MESH_SUFFIXES:
            scene = _single_mesh_scene(path, effects)
        elif path.suffix.lower() == ".toml" or path.exists():
            scene = load_scene_toml(path, effects)
        else:
            raise FileNotFoundError(
                f"load_scene: {key!r} is neither a built-in scene ({', '.join(BUILTINS)}) "
                f"nor an existing file nor a scene file; scene files: "
                f"{catalog.available('scenes', catalog.local_configs(Path.cwd()))}")
    return scene


def _single_mesh_scene(path: Path, effects) -> Scene:
    if not path.is_file():
        raise FileNotFoundError(f"load_scene: mesh file {path} not found")
    materials, textures = [], []
    parts = load_mesh_file(path, materials, textures)
    pts = np.concatenate([p.positions for p in parts])
    lo, hi = pts.min(0), pts.max(0)
    centre, radius = (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 1e-3)
    cam = look_at(centre + np.array([0.3, 0.4, 1.0]) * 2.0 * radius, centre,
                  near=radius * 0.01, far=radius * 10)
    lights = make_lights([((0.4, 0.8, 0.45), 2.5)], ambient=0.1)
    return build_scene(parts, materials, textures, lights, cam, name=path.stem,
                       description=f"mesh file {path.name}", effects=effects)
