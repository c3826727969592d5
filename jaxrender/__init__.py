"""jaxrender: study real-time shading architectures on identical scenes, measured in JAX.

In Python::

    import jaxrender
    scene = jaxrender.load_scene("spheres")
    frame = jaxrender.render(scene, jaxrender.default_camera(scene), "deferred")

``load_scene``, ``render``, ``render_sequence`` and ``run_study`` (``jaxrender.api``),
``default_camera``, ``camera_path`` (pan, orbit, dolly, jitter), ``metrics``,
``list_pipelines``, ``list_scenes``. The names are imported on first use, so that
``import jaxrender.raster`` (or the command line's ``--help``) stays light.
"""

from __future__ import annotations

import importlib

from jaxrender.version import VERSION as __version__  # noqa: F401

_NAMES = {
    "load_scene": ("jaxrender.api", "load_scene"),
    "render": ("jaxrender.api", "render"),
    "render_sequence": ("jaxrender.api", "render_sequence"),
    "run_study": ("jaxrender.api", "run_study"),
    "default_camera": ("jaxrender.scene", "default_camera"),
    "list_pipelines": ("jaxrender.pipelines.registry", "list_pipelines"),
    "list_scenes": ("jaxrender.scene", "list_builtin_scenes"),
    "camera_path": ("jaxrender.scene.camera_path", None),
    "metrics": ("jaxrender.metrics", None),
}

__all__ = ["__version__", *_NAMES]


def __getattr__(name: str):
    if name not in _NAMES:
        raise AttributeError(f"module 'jaxrender' has no attribute {name!r}")
    module, attr = _NAMES[name]
    value = importlib.import_module(module)
    value = value if attr is None else getattr(value, attr)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_NAMES))
