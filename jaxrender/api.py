"""jaxrender in Python: load a scene, render it through a pipeline (one frame or a camera path),
score it, run a study. ``jaxrender.render`` and friends are these functions."""

from __future__ import annotations

from pathlib import Path

from jaxrender.figures import draw_run_figures
from jaxrender.pipelines.registry import Pipeline, get_pipeline, make_config
from jaxrender.scene import Scene
from jaxrender.shading import load_lit_scene
from jaxrender.study import RunResult, load_study, shader_cost
from jaxrender.study.backend import with_shader_cost
from jaxrender.study import run_study as run_loaded_study
from jaxrender.types import Frame


def load_scene(name_or_path: str | Path, **size_params) -> Scene:
    """A built-in scene by name (``size_params`` go to its builder), a scene TOML file or a
    mesh file, ready to render: a scene with shadows has its shadow map drawn."""
    return load_lit_scene(name_or_path, **size_params)


def _prepare(scene, pipeline: str | Pipeline, params: dict):
    """(scene, pipeline, config) as a study entry with these params renders them:
    ``shader_cost`` sets the scene's, the rest build the pipeline's config."""
    params, cost = shader_cost.split(params)
    pipe = get_pipeline(pipeline) if isinstance(pipeline, str) else pipeline
    return with_shader_cost(scene, cost), pipe, make_config(pipe, **params)


def render(scene: Scene, camera, pipeline: str | Pipeline = "deferred", **params) -> Frame:
    """One frame of ``pipeline`` (a registered name, ``jaxrender.list_pipelines()``), its
    config built from ``params``: ``width``, ``height`` and the pipeline's own keys (an
    unknown key raises, naming it), and ``shader_cost`` as in a study's pipeline entry (the
    scene's extra light layers). A Frame: ``image`` (H, W, 3) linear RGB, ``counts``."""
    scene, pipe, cfg = _prepare(scene, pipeline, params)
    return pipe.render(scene, camera, cfg)


def render_sequence(scene: Scene, cameras, pipeline: str | Pipeline = "deferred", *,
                    warmup_frames: int = 0, **params) -> Frame:
    """The frames of a camera path (a CameraPath, a list of cameras, or a Camera batched over
    a leading axis), the pipeline's state carried from frame to frame (checkerboard's history,
    object space's store) in one compiled program; the first ``warmup_frames`` are rendered
    and dropped. A Frame with ``image`` (T, H, W, 3) and per-frame ``counts``."""
    scene, pipe, cfg = _prepare(scene, pipeline, params)
    return pipe.render_sequence(scene, cameras, cfg, warmup_frames=warmup_frames)


def run_study(study: str | Path, *, out: str | Path | None = None, frames: int | None = None,
              resolution: str | tuple | None = None, configs: str | Path | None = None,
              force: bool = False, figures: bool = True, progress: bool = True,
              log=print, devices: int | None = None) -> RunResult:
    """Run a study file (or a bundled study by name, ``jaxrender studies``) as ``jaxrender
    study`` does: results in ``out`` (default ``runs/NAME``), resuming what is stored unless
    ``force``; ``frames`` and ``resolution`` override the file's; ``devices``: how many local
    devices the sequences spread over (default: all). Returns the RunResult
    (``rows``, ``summary``, ``out_dir``) after drawing its figures."""
    spec = load_study(study, configs=Path(configs) if configs else None)
    spec = spec.with_overrides(frames=frames, resolution=resolution)
    result = run_loaded_study(spec, Path(out) if out else Path("runs") / spec.name,
                              force=force, progress=progress, log=log, devices=devices)
    if figures:
        draw_run_figures(result, log=log)
    return result
