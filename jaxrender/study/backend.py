"""What the study takes from the rest of jaxrender: pipelines, scenes, camera paths, metrics.

One module, so that the study's tests can put small doubles in place of each piece
(tests/study/doubles.py) and run the runner, store and cache end to end in seconds.
"""

from __future__ import annotations

import inspect
from typing import Any

import jax
import numpy as np

from jaxrender import metrics
from jaxrender import scene as scenes
from jaxrender.pipelines import motion_field as motion_fields
from jaxrender.pipelines import registry
from jaxrender.scene.builtin import BUILTINS
from jaxrender.scene.camera_path import PATH_TYPES
from jaxrender.scene.hard_cases import HARD_SCENES
from jaxrender.shading import load_lit_scene
from jaxrender.errors import Unavailable, UserError

# ---------------------------------------------------------------- pipelines


def registered_pipelines() -> list[str]:
    return [p.name for p in registry.list_pipelines()]


def pipeline(name: str):
    """The registered Pipeline, or Unavailable naming what is registered."""
    try:
        return registry.get_pipeline(name)
    except KeyError:
        known = ", ".join(registered_pipelines()) or "(none)"
        raise Unavailable(f"pipeline {name!r} is not registered; registered: {known}") from None


def make_config(name: str, width: int, height: int, params: dict):
    return registry.make_config(name, width=width, height=height, **params)


# ---------------------------------------------------------------- scenes


def builtin_scenes() -> list[tuple[str, str]]:
    """(name, one-line description) of each built-in scene."""
    return scenes.list_builtin_scenes()


def builtin_scene_names() -> list[str]:
    return [name for name, _ in builtin_scenes()] + list(HARD_SCENES)


def scene_params(name: str) -> dict | None:
    """{size parameter: default} of a built-in scene's builder, or None when unknown."""
    fn = BUILTINS.get(name) or HARD_SCENES.get(name)
    if fn is None:
        return None
    return {p.name: p.default for p in inspect.signature(fn).parameters.values()
            if p.kind is p.KEYWORD_ONLY or p.kind is p.POSITIONAL_OR_KEYWORD}


def load_scene(source: str, params: dict) -> Any:
    """``source`` is a built-in name or a path to a scene TOML file."""
    try:
        return load_lit_scene(source, **params)
    except (FileNotFoundError, TypeError, ValueError) as e:  # ValueError: a bad scene file
        raise UserError(f"scene {source!r}: {e}") from None


def default_camera(scene):
    return scenes.default_camera(scene)


# ---------------------------------------------------------------- camera paths


def _split_cameras(out, frames: int) -> list:
    """Cameras from a CameraPath (batched cameras) or a list of cameras."""
    if hasattr(out, "cameras"):
        out = out.cameras
    if isinstance(out, (list, tuple)):
        cams = list(out)
    else:
        n = np.shape(jax.tree_util.tree_leaves(out)[0])[0]
        cams = [jax.tree_util.tree_map(lambda a, i=i: a[i], out) for i in range(n)]
    if len(cams) != frames:
        raise Unavailable(f"camera path returned {len(cams)} cameras for {frames} frames")
    return cams


def make_cameras(scene, path, width: int, height: int) -> list:
    """One camera per frame of ``path`` (a PathSpec), starting from the scene's default."""
    build = PATH_TYPES[path.type].build
    out = build(default_camera(scene), path.frames, width, height, **dict(path.params))
    return _split_cameras(out, path.frames)


# ---------------------------------------------------------------- metrics


def _value(x) -> float:
    if isinstance(x, tuple):
        x = x[0]
    return float(np.asarray(x, np.float64).reshape(-1)[0])


def frame_metrics(test: np.ndarray, ref: np.ndarray, names) -> tuple[dict, np.ndarray]:
    """Per-frame metrics of linear RGB (H, W, 3) images, display-referred (``to_display``:
    clamp, sRGB encode) as the published numbers are, and an error map for the figures
    (the ``error_map`` metric's map when it is computed, else the mean absolute display
    difference)."""
    t, r = metrics.to_display(test), metrics.to_display(ref)
    out: dict = {}
    err_map = None
    for name in names:
        m = metrics.METRICS[name]
        if m.sequence:
            continue
        res = m.fn(t, r)
        out[name] = _value(res)
        if m.error_map and isinstance(res, tuple) and len(res) > 1:
            err_map = np.asarray(res[1], np.float32)
    if err_map is None or err_map.shape[:2] != test.shape[:2]:
        err_map = np.abs(np.asarray(t) - np.asarray(r)).mean(axis=-1)
    return out, np.asarray(err_map).reshape(test.shape[:2]).astype(np.float32)


def sequence_metrics(tests: np.ndarray, refs: np.ndarray, names, motion=None
                     ) -> tuple[dict, list]:
    """Metrics of a whole (T, H, W, 3) sequence (the value is repeated on each frame's row)
    and the per-frame temporal error of each frame against its predecessor (NaN at frame 0),
    whose mean over frames 1.. is the sequence's value. Display-referred, as frame_metrics.
    ``motion``: the sequence's motion field (``motion_field``), for the metrics that warp."""
    t = tests.shape[0]
    names = [n for n in names if metrics.METRICS[n].sequence]
    per_frame = [float("nan")] * t
    if not names:
        return {}, per_frame
    if t < 2:
        return {n: float("nan") for n in names}, per_frame
    ti, ri = metrics.to_display(tests), metrics.to_display(refs)
    out = {}
    for name in names:
        m = metrics.METRICS[name]
        if m.motion and motion is None:
            raise ValueError(f"metric {name!r} needs the sequence's motion field")
        out[name] = _value(m.fn(ti, ri, motion) if m.motion else m.fn(ti, ri))
    if "temporal_error" in names:
        fn = metrics.METRICS["temporal_error"].fn
        per_frame = [float("nan")] + [_value(fn(ti[i - 1:i + 1], ri[i - 1:i + 1]))
                                      for i in range(1, t)]
    return out, per_frame


def needs_motion(names) -> bool:
    return any(metrics.METRICS[n].motion for n in names)


def motion_field(scene, cameras, width: int, height: int, start: int):
    """The motion field of a rendered path (``pipelines.motion_field``)."""
    return motion_fields.motion_field(scene, cameras, width, height, start=start)
