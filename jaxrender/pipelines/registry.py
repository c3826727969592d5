"""The pipeline registry: one protocol for every pipeline, one ``type`` string per pipeline.

A pipeline is three functions over its static config, so that every pipeline is compiled,
checked and run by the same code (``pipelines.program``):

- ``prepare(scene, cfg) -> Static``: host-side work done once per scene (object-space shade
  sheets); default: nothing (None);
- ``init(scene, static, camera, cfg) -> State``: what a sequence carries from frame to frame
  (history, a store); default: nothing (an empty tuple);
- ``step(scene, static, state, camera, t, cfg) -> (Frame, State)``: frame ``t`` (traced int32).

``@register("name", ConfigClass, init=..., prepare=...)`` registers a ``step``;
``@register_frame("name", ConfigClass)`` registers a stateless ``frame(scene, camera, cfg)``.
Both return the function unchanged; a module exposes ``render = REGISTRY["name"].render``.
From these the registry's ``Pipeline`` builds ``render(scene, camera, cfg) -> Frame`` (one step
from ``init``) and ``render_sequence(scene, cameras, cfg) -> Frame`` (a ``lax.scan`` of
``step``), both through ``pipelines.program``: one jit site and one overflow check for all.

A config class is a frozen (hashable, hence static under jit) dataclass deriving from
``RenderConfig``; the study builds it from TOML with ``make_config``, which rejects unknown keys
by name. Fields named in the class attribute ``TRACED_FIELDS`` are passed to the compiled
program as arrays instead (a DACS threshold sweep compiles once); fields in
``OUTPUT_NEUTRAL`` change how the work is laid out but never a pixel or a count of the result
(chunk sizes, capacities), which tests check.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, ClassVar

import jaxrender.pipelines.program as program


TAA_HISTORY_FILTERS = ("bilinear", "catmull_rom")
TAA_CLIPS = ("clamp", "variance")
TAA_PHASES = (8, 16)


@dataclass(frozen=True)
class RenderConfig:
    """Static settings shared by every pipeline: the output resolution in pixels, and the
    temporal anti-aliasing any pipeline can add after its resolve (``pipelines.taa``):

    taa: jitter the projection and blend each frame into the reprojected history.
    taa_alpha: weight of the new frame in the exponential blend, in (0, 1].
    taa_phases: length of the Halton(2, 3) jitter sequence (8 or 16).
    taa_history: how the history is sampled at the motion vector: bilinear or catmull_rom.
    taa_clip: how the history is bounded by the new frame's 3x3 neighbourhood in YCoCg: clamp
        (to its min/max box) or variance (clipped towards its mean, into mean +- sigma).
    The taa_* settings are refused without ``taa``."""

    width: int = 320
    height: int = 180
    taa: bool = False
    taa_alpha: float = 0.1
    taa_phases: int = 8
    taa_history: str = "bilinear"
    taa_clip: str = "clamp"

    TRACED_FIELDS: ClassVar[tuple[str, ...]] = ()
    OUTPUT_NEUTRAL: ClassVar[tuple[str, ...]] = ()

    def __post_init__(self):
        if not (0.0 < float(self.taa_alpha) <= 1.0):
            raise ValueError(f"taa_alpha must be in (0, 1], got {self.taa_alpha}")
        if int(self.taa_phases) not in TAA_PHASES:
            raise ValueError(f"taa_phases must be 8 or 16, got {self.taa_phases}")
        if self.taa_history not in TAA_HISTORY_FILTERS:
            raise ValueError(f"taa_history must be one of {', '.join(TAA_HISTORY_FILTERS)}, "
                             f"got {self.taa_history!r}")
        if self.taa_clip not in TAA_CLIPS:
            raise ValueError(f"taa_clip must be one of {', '.join(TAA_CLIPS)}, "
                             f"got {self.taa_clip!r}")
        if not self.taa:
            for f in dataclasses.fields(RenderConfig):
                if f.name.startswith("taa_") and getattr(self, f.name) != f.default:
                    raise ValueError(f"{f.name} has no effect without taa = true")

    def overflow_hint(self) -> str:
        """What to raise when a frame of this config overflows (part of the error message)."""
        return "a capacity of the pipeline was exceeded; see the Frame counts"


def no_prepare(scene, cfg):
    return None


def no_state(scene, static, camera, cfg):
    return ()


@dataclass(frozen=True)
class Pipeline:
    """A registered pipeline. Hashable: it is a static argument of the compiled programs."""

    name: str
    config_cls: type
    step: Callable  # step(scene, static, state, camera, t, cfg) -> (Frame, State)
    init: Callable = no_state
    prepare: Callable = no_prepare
    description: str = ""

    @property
    def stateful(self) -> bool:
        return self.init is not no_state

    @property
    def prepares(self) -> bool:
        """Has host-side preparation per scene (object-space sheets)."""
        return self.prepare is not no_prepare

    def render(self, scene, camera, cfg, *, t=0):
        """Frame ``t`` (default 0: the scene's animation clock and TAA's jitter phase) from
        ``init``: a Frame with image (H, W, 3)."""
        return program.render(self, scene, camera, cfg, t=t)

    def render_sequence(self, scene, cameras, cfg, *, warmup_frames: int = 0):
        """Frames of a camera path (CameraPath, a Camera batched over a leading axis T, or a
        list of cameras), the state carried from frame to frame; the first ``warmup_frames``
        are rendered and dropped. A Frame with image (T', H, W, 3), counts (T',)."""
        return program.render_sequence(self, scene, cameras, cfg, warmup_frames=warmup_frames)


REGISTRY: dict[str, Pipeline] = {}


def _check_config_cls(name: str, config_cls: type) -> None:
    if not (dataclasses.is_dataclass(config_cls) and issubclass(config_cls, RenderConfig)):
        raise TypeError(f"pipeline {name!r}: config must be a RenderConfig dataclass")
    fields = {f.name for f in dataclasses.fields(config_cls)}
    for attr in ("TRACED_FIELDS", "OUTPUT_NEUTRAL"):
        unknown = sorted(set(getattr(config_cls, attr)) - fields)
        if unknown:
            raise TypeError(f"pipeline {name!r}: {attr} names {unknown[0]!r}, not a field")


def register(name: str, config_cls: type, description: str = "", *,
             init: Callable = no_state, prepare: Callable = no_prepare, replace: bool = False):
    """Register ``step(scene, static, state, camera, t, cfg) -> (Frame, State)`` under
    ``name``; returns ``step`` unchanged. ``replace=True`` lets a test swap an entry."""
    _check_config_cls(name, config_cls)

    def wrap(step: Callable) -> Callable:
        if name in REGISTRY and not replace:
            raise ValueError(f"pipeline {name!r} is registered twice")
        doc = description or ((step.__doc__ or "").strip().splitlines() or [""])[0]
        REGISTRY[name] = Pipeline(name, config_cls, step, init, prepare, doc)
        return step

    return wrap


@dataclass(frozen=True)
class FrameStep:
    """The step of a stateless pipeline: ``frame(scene, camera, cfg)``, state passed through.
    A frozen dataclass (hashable, equal by its function) so that it is a stable static."""

    frame: Callable

    def __call__(self, scene, static, state, camera, t, cfg):
        return self.frame(scene, camera, cfg), state


def register_frame(name: str, config_cls: type, description: str = "", *,
                   replace: bool = False):
    """Register a stateless pipeline's ``frame(scene, camera, cfg) -> Frame``; returns
    ``frame`` unchanged (it must stay reachable under its own name: worker processes receive
    it pickled by reference)."""

    def wrap(frame: Callable) -> Callable:
        doc = description or ((frame.__doc__ or "").strip().splitlines() or [""])[0]
        register(name, config_cls, doc, replace=replace)(FrameStep(frame))
        return frame

    return wrap


def get_pipeline(name: str) -> Pipeline:
    """The registered pipeline ``name``. Importing any module of ``jaxrender.pipelines`` runs the
    package's ``__init__`` first, which imports (and so registers) every built-in pipeline."""
    try:
        return REGISTRY[name]
    except KeyError:
        known = ", ".join(sorted(REGISTRY)) or "(none)"
        raise KeyError(f"unknown pipeline {name!r}; registered pipelines: {known}") from None


def make_config(pipeline: str | Pipeline, **params):
    """The config of ``pipeline`` (a registered name, or a Pipeline itself) from keyword
    parameters; unknown keys raise, naming the key."""
    pipe = get_pipeline(pipeline) if isinstance(pipeline, str) else pipeline
    name, cls = pipe.name, pipe.config_cls
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(params) - fields)
    if unknown:
        raise KeyError(
            f"pipeline {name!r} has no parameter {unknown[0]!r}; "
            f"its parameters are: {', '.join(sorted(fields))}"
        )
    return cls(**params)


def list_pipelines() -> list[Pipeline]:
    return [REGISTRY[k] for k in sorted(REGISTRY)]
