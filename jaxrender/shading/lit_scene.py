"""``load_lit_scene``: a scene ready to shade, its shadow map rendered when it asks for shadows.

Loading a scene (``jaxrender.scene.load_scene``) only describes it; the shadow map is a
rasterizer pass, so it is rendered here, above the rasterizer in the data flow.
"""

from __future__ import annotations

from pathlib import Path

from jaxrender.scene.loader import load_scene
from jaxrender.scene.scene import Scene
from jaxrender.shading.shadow import with_shadow_map


def load_lit_scene(name_or_path: str | Path, **kw) -> Scene:
    """``scene.load_scene(name_or_path, **kw)``, with its shadow map rendered when the scene's
    effects ask for shadows, so ``shade`` can use it at once."""
    scene = load_scene(name_or_path, **kw)
    if scene.effects.shadows:
        scene = with_shadow_map(scene)
    return scene
