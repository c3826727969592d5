"""The study's only doors into the rest of jaxrender: pipelines, scenes, camera paths, metrics.

Everything is imported lazily, so that a piece that has not landed yet gives one clear error
(``Unavailable``) instead of an ImportError deep in a traceback. Tests replace these functions
with monkeypatch to run the study machinery on tiny fake scenes and pipelines.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any

import numpy as np

from jaxrender.study.errors import Unavailable

# Metric names a study may ask for; counts are always recorded.
METRICS = ("rmse", "psnr", "mssim", "flip", "delta_e", "temporal_error")
# Camera path types handled here without jaxrender.scene.camera_path.
BUILTIN_PATH_TYPES = ("static",)
_CAMERA_PATH_TYPES = ("pan", "orbit", "dolly", "jitter")


def _module(name: str, what: str):
    try:
        return importlib.import_module(name)
    except ImportError as e:
        raise Unavailable(f"{what} needs {name}, which cannot be imported: {e}") from None


def _attr(module_name: str, attr: str, what: str):
    mod = _module(module_name, what)
    fn = getattr(mod, attr, None)
    if fn is None:
        raise Unavailable(f"{what} needs {module_name}.{attr}, which does not exist yet")
    return fn


# ---------------------------------------------------------------- pipelines


def registered_pipelines() -> list[str]:
    from jaxrender.pipelines import registry

    return [p.name for p in registry.list_pipelines()]


def pipeline(name: str):
    """The registered Pipeline, or Unavailable naming what is registered."""
    from jaxrender.pipelines import registry

    try:
        return registry.get_pipeline(name)
    except KeyError:
        known = ", ".join(registered_pipelines()) or "(none yet)"
        raise Unavailable(f"pipeline {name!r} is not registered; registered: {known}") from None


def make_config(name: str, width: int, height: int, params: dict):
    from jaxrender.pipelines import registry

    return registry.make_config(name, width=width, height=height, **params)


# ---------------------------------------------------------------- scenes


def builtin_scene_names() -> list[str]:
    fn = _attr("jaxrender.scene", "list_builtin_scenes", "listing the built-in scenes")
    return [entry[0] if isinstance(entry, (tuple, list)) else str(entry) for entry in fn()]


def builtin_scenes() -> list[tuple[str, str]]:
    fn = _attr("jaxrender.scene", "list_builtin_scenes", "listing the built-in scenes")
    out = []
    for entry in fn():
        if isinstance(entry, (tuple, list)):
            out.append((str(entry[0]), str(entry[1]) if len(entry) > 1 else ""))
        else:
            out.append((str(entry), ""))
    return out


def load_scene(source: str, params: dict) -> Any:
    """``source`` is a built-in name or a path to a scene TOML file."""
    fn = _attr("jaxrender.scene", "load_scene", "loading a scene")
    return fn(source, **params)


def default_camera(scene):
    fn = _attr("jaxrender.scene", "default_camera", "the scene's default camera")
    return fn(scene)


# ---------------------------------------------------------------- camera paths


def path_types() -> list[str]:
    """Camera path types a study may name: 'static' and those camera_path provides."""
    types = list(BUILTIN_PATH_TYPES)
    try:
        cp = importlib.import_module("jaxrender.scene.camera_path")
    except ImportError:
        return types
    declared = getattr(cp, "PATH_TYPES", None)
    if declared is not None:
        names = list(declared)
    elif hasattr(cp, "make_path"):
        names = list(_CAMERA_PATH_TYPES)
    else:
        names = [t for t in _CAMERA_PATH_TYPES if callable(getattr(cp, t, None))]
    return types + [t for t in names if t not in types]


def _call_with(fn, args: tuple, kwargs: dict):
    """Call fn with those keyword arguments it accepts (width/height/frames/scene are optional)."""
    sig = inspect.signature(fn)
    takes_any = any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values())
    optional = {"width", "height", "scene", "aspect"}
    kw = {k: v for k, v in kwargs.items() if k not in optional or takes_any or k in sig.parameters}
    return fn(*args, **kw)


def _split_cameras(out, frames: int) -> list:
    """Cameras from what a path function returns: a list of cameras, of (camera, previous)
    pairs, or one Camera batched over a leading frame axis."""
    import jax

    if hasattr(out, "cameras"):
        out = out.cameras
    if isinstance(out, (list, tuple)):
        cams = [c[0] if isinstance(c, tuple) else c for c in out]
    else:
        n = np.shape(jax.tree_util.tree_leaves(out)[0])[0]
        cams = [jax.tree_util.tree_map(lambda a, i=i: a[i], out) for i in range(n)]
    if len(cams) != frames:
        raise Unavailable(f"camera path returned {len(cams)} cameras for {frames} frames")
    return cams


def make_cameras(scene, path, width: int, height: int) -> list:
    """One camera per frame of ``path`` (a PathSpec), starting from the scene's default."""
    base = default_camera(scene)
    if path.type == "static":
        return [base] * path.frames
    cp = _module("jaxrender.scene.camera_path", f"camera path {path.type!r}")
    params = dict(path.params)
    extra = {"width": width, "height": height, "scene": scene, "aspect": width / height}
    if hasattr(cp, "make_path"):
        out = _call_with(cp.make_path, (path.type, base, path.frames), {**params, **extra})
    elif callable(getattr(cp, path.type, None)):
        out = _call_with(getattr(cp, path.type), (base, path.frames), {**params, **extra})
    else:
        raise Unavailable(f"jaxrender.scene.camera_path has no camera path {path.type!r}")
    return _split_cameras(out, path.frames)


# ---------------------------------------------------------------- metrics


def _value(x) -> float:
    if isinstance(x, tuple):
        x = x[0]
    return float(np.asarray(x, np.float64).reshape(-1)[0])


def _map(x):
    if isinstance(x, tuple) and len(x) > 1:
        return np.asarray(x[1], np.float32)
    return None


def frame_metrics(test: np.ndarray, ref: np.ndarray, names) -> tuple[dict, np.ndarray]:
    """Per-frame metrics of linear RGB (H, W, 3) images and an error map for the figures
    (FLIP's map when FLIP is computed, else the mean absolute difference)."""
    names = [n for n in names if n != "temporal_error"]
    out: dict = {}
    err_map = None
    if names:
        m = _module("jaxrender.metrics", "scoring images")
        fns = {
            "rmse": ("rmse", lambda f: f(test, ref)),
            "psnr": ("psnr", lambda f: f(test, ref)),
            "mssim": ("ssim", lambda f: f(test, ref)),
            "flip": ("flip", lambda f: f(ref, test)),
            "delta_e": ("delta_e2000", lambda f: f(test, ref)),
        }
        for name in names:
            attr, call = fns[name]
            fn = getattr(m, attr, None)
            if fn is None:
                raise Unavailable(f"metric {name!r} needs jaxrender.metrics.{attr}, not there yet")
            res = call(fn)
            out[name] = _value(res)
            if name == "flip":
                err_map = _map(res)
    if err_map is None or err_map.shape[:2] != test.shape[:2]:
        err_map = np.abs(test - ref).mean(axis=-1)
    return out, err_map.reshape(test.shape[:2]).astype(np.float32)


def sequence_metrics(tests: np.ndarray, refs: np.ndarray, names) -> tuple[dict, list]:
    """Metrics of a whole (T, H, W, 3) sequence (the value is repeated on each frame's row)
    and the per-frame temporal error of each frame against its predecessor (NaN at frame 0),
    whose mean over frames 1.. is the sequence's value."""
    t = tests.shape[0]
    if "temporal_error" not in names:
        return {}, [float("nan")] * t
    if t < 2:
        return {"temporal_error": float("nan")}, [float("nan")]
    fn = _attr("jaxrender.metrics", "temporal_error", "metric 'temporal_error'")
    per_frame = [float("nan")] + [_value(fn(tests[i - 1:i + 1], refs[i - 1:i + 1]))
                                  for i in range(1, t)]
    return {"temporal_error": _value(fn(tests, refs))}, per_frame
