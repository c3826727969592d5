"""What the study takes from the rest of jaxrender: pipelines, scenes, camera paths, metrics.

One module, so that the study's tests can put small doubles in place of each piece
(tests/study/doubles.py) and run the runner, store and cache end to end in seconds.
"""

from __future__ import annotations

import dataclasses
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
    """``source`` is a built-in name or a path to a scene TOML file; a ``shader_cost`` in
    ``params`` sets its shader cost (``with_shader_cost``)."""
    params = dict(params)
    cost = params.pop("shader_cost", None)
    try:
        return with_shader_cost(load_lit_scene(source, **params), cost)
    except (FileNotFoundError, TypeError, ValueError) as e:  # ValueError: a bad scene file
        raise UserError(f"scene {source!r}: {e}") from None


def with_shader_cost(scene, cost: int | None):
    """The scene with its ``Effects.shader_cost`` set to ``cost`` (None: unchanged)."""
    if cost is None:
        return scene
    if getattr(scene, "effects", None) is None:
        raise UserError(f"shader_cost: scene {getattr(scene, 'name', '?')!r} has no shader "
                        "effects to set a cost on")
    return dataclasses.replace(scene, effects=scene.effects.replace(shader_cost=int(cost)))


def shader_cost(scene) -> int | None:
    """The scene's shader cost, or None for a scene without effects."""
    effects = getattr(scene, "effects", None)
    return None if effects is None else int(effects.shader_cost)


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
    """The per-image metrics among ``names`` of linear RGB (H, W, 3) images as floats, through
    ``metrics.image_metrics`` (display-referred, as the published numbers are), and the error
    map the figures show."""
    per_image = [n for n in names if not metrics.METRICS[n].sequence]
    values, err_map = metrics.image_metrics(test, ref, names=per_image, error_map=True)
    return ({n: _value(v) for n, v in values.items()},
            np.asarray(err_map, np.float32).reshape(test.shape[:2]))


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
