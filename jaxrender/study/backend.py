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

from jaxrender.study.errors import Unavailable, UserError

# Metric names a study may ask for; counts are always recorded.
METRICS = ("rmse", "psnr", "mssim", "flip", "delta_e", "temporal_error")


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


def builtin_scenes() -> list[tuple[str, str]]:
    fn = _attr("jaxrender.scene", "list_builtin_scenes", "listing the built-in scenes")
    out = []
    for entry in fn():
        if isinstance(entry, (tuple, list)):
            out.append((str(entry[0]), str(entry[1]) if len(entry) > 1 else ""))
        else:
            out.append((str(entry), ""))
    return out


def builtin_scene_names() -> list[str]:
    from jaxrender.scene.hard_cases import HARD_SCENES

    return [name for name, _ in builtin_scenes()] + list(HARD_SCENES)


def scene_params(name: str) -> dict | None:
    """{size parameter: default} of a built-in scene's builder, or None when unknown."""
    try:
        from jaxrender.scene.builtin import BUILTINS
    except ImportError:
        return None
    from jaxrender.scene.hard_cases import HARD_SCENES

    fn = BUILTINS.get(name) or HARD_SCENES.get(name)
    if fn is None:
        return None
    return {p.name: p.default for p in inspect.signature(fn).parameters.values()
            if p.kind is p.KEYWORD_ONLY or p.kind is p.POSITIONAL_OR_KEYWORD}


def load_scene(source: str, params: dict) -> Any:
    """``source`` is a built-in name or a path to a scene TOML file."""
    fn = _attr("jaxrender.shading", "load_lit_scene", "loading a scene")
    try:
        return fn(source, **params)
    except (FileNotFoundError, TypeError) as e:
        raise UserError(f"scene {source!r}: {e}") from None
    except ValueError as e:  # SceneConfigError and friends: a bad scene file
        raise UserError(f"scene {source!r}: {e}") from None


def default_camera(scene):
    fn = _attr("jaxrender.scene", "default_camera", "the scene's default camera")
    return fn(scene)


# ---------------------------------------------------------------- camera paths

# Parameters of each camera path type a study may set: name -> (default or None if required,
# expected Python type). "static" repeats the scene's default camera.
PATH_PARAMS: dict[str, dict] = {
    "static": {},
    "pan": {"pixels_per_frame": (None, float), "direction": ("horizontal", str)},
    "orbit": {"degrees_per_frame": (None, float), "distance": (4.0, float),
              "center": ((), list), "radius": (0.0, float)},
    "dolly": {"distance_per_frame": (None, float)},
    "jitter": {"pattern": ("halton", str)},
}


def path_types() -> list[str]:
    """Camera path types a study may name: 'static' and those camera_path provides."""
    try:
        cp = importlib.import_module("jaxrender.scene.camera_path")
    except ImportError:
        return ["static"]
    return ["static"] + [t for t in PATH_PARAMS if t != "static" and callable(getattr(cp, t,
                                                                                     None))]


def _split_cameras(out, frames: int) -> list:
    """Cameras from a CameraPath (batched cameras), a list of cameras or (camera, previous)."""
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
    n, params = path.frames, dict(path.params)
    if path.type == "static":
        return [base] * n
    cp = _module("jaxrender.scene.camera_path", f"camera path {path.type!r}")
    if path.type == "pan":
        out = cp.pan(base, n, float(params["pixels_per_frame"]), height,
                     direction=params.get("direction", "horizontal"))
    elif path.type == "dolly":
        out = cp.dolly(base, n, float(params["distance_per_frame"]))
    elif path.type == "jitter":
        out = cp.jitter(base, n, width, height, pattern=params.get("pattern", "halton"))
    elif path.type == "orbit":
        # around a point `distance` ahead of the default camera, starting where it stands
        eye = np.asarray(base.eye, np.float64)
        fwd = -np.asarray(base.rotation, np.float64)[2]
        center = np.asarray(params.get("center") or eye + fwd * params.get("distance", 4.0))
        rel = eye - center
        radius = float(params.get("radius") or np.hypot(rel[0], rel[2]) or 1.0)
        out = cp.orbit(center, radius, n, float(params["degrees_per_frame"]), height=rel[1],
                       start_deg=float(np.rad2deg(np.arctan2(rel[0], rel[2]))),
                       fov_y_deg=float(np.rad2deg(float(base.fov_y))),
                       near=float(base.near), far=float(base.far))
    else:
        raise Unavailable(f"camera path type {path.type!r} is not supported")
    return _split_cameras(out, n)


# ---------------------------------------------------------------- metrics


def _value(x) -> float:
    if isinstance(x, tuple):
        x = x[0]
    return float(np.asarray(x, np.float64).reshape(-1)[0])


def _map(x):
    if isinstance(x, tuple) and len(x) > 1:
        return np.asarray(x[1], np.float32)
    return None


def _display(x):
    fn = _attr("jaxrender.metrics", "to_display", "scoring images")
    return fn(x)


def frame_metrics(test: np.ndarray, ref: np.ndarray, names) -> tuple[dict, np.ndarray]:
    """Per-frame metrics of linear RGB (H, W, 3) images, display-referred (``to_display``:
    clamp, sRGB encode) as the published numbers are, and an error map for the figures
    (FLIP's map when FLIP is computed, else the mean absolute display difference)."""
    names = [n for n in names if n != "temporal_error"]
    out: dict = {}
    err_map = None
    m = _module("jaxrender.metrics", "scoring images")
    t, r = _display(test), _display(ref)
    fns = {
        "rmse": ("rmse", lambda f: f(t, r)),
        "psnr": ("psnr", lambda f: f(t, r)),
        "mssim": ("ssim", lambda f: f(t, r)),
        "flip": ("flip", lambda f: f(r, t)),
        "delta_e": ("delta_e2000", lambda f: f(t, r)),
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
        err_map = np.abs(np.asarray(t) - np.asarray(r)).mean(axis=-1)
    return out, np.asarray(err_map).reshape(test.shape[:2]).astype(np.float32)


def sequence_metrics(tests: np.ndarray, refs: np.ndarray, names) -> tuple[dict, list]:
    """Metrics of a whole (T, H, W, 3) sequence (the value is repeated on each frame's row)
    and the per-frame temporal error of each frame against its predecessor (NaN at frame 0),
    whose mean over frames 1.. is the sequence's value. Display-referred, as frame_metrics."""
    t = tests.shape[0]
    if "temporal_error" not in names:
        return {}, [float("nan")] * t
    if t < 2:
        return {"temporal_error": float("nan")}, [float("nan")]
    fn = _attr("jaxrender.metrics", "temporal_error", "metric 'temporal_error'")
    ti, ri = _display(tests), _display(refs)
    per_frame = [float("nan")] + [_value(fn(ti[i - 1:i + 1], ri[i - 1:i + 1]))
                                  for i in range(1, t)]
    return {"temporal_error": _value(fn(ti, ri))}, per_frame
