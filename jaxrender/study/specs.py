"""The validated study objects: frozen dataclasses a study file is read into (``schema``), and
written back as the resolved ``study.toml`` (``to_toml``)."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any

from jaxrender.errors import UserError
from jaxrender.metrics import DEFAULT_METRICS, METRICS
from jaxrender.parsing import parse_resolution

FIGURES = (
    "image_grid",
    "pareto_time",
    "pareto_count",
    "temporal",
    "dacs_decisions",
    "object_space_marking",
    "tads_samples",
    "visbuffer_waves",
    "time_work",
    "summary_table",
)
TIMED_OUTPUTS = ("images", "all")  # the choices of [timing] outputs
SSIM_MIN_SIDE = 11  # the 11-tap Gaussian window of Wang et al.



def _field(default=dataclasses.MISSING, **meta):
    """A spec field: ``lo`` bounds an integer, ``toml=False`` keeps it out of the file,
    ``empty=True`` lets a string be empty, ``table=True`` wants a table, ``required=True``
    must be given although the dataclass has a default (for field order)."""
    return field(default=default, metadata=meta)


# ------------------------------------------------------------------ the validated objects


@dataclass(frozen=True)
class SceneSpec:
    label: str  # the name rows use
    source: str = _field(toml=False)  # built-in name, or an absolute path to a scene TOML file
    params: tuple[tuple[str, Any], ...] = _field((), table=True)
    file_hash: str = _field("", toml=False)  # sha256 of the scene file, for the cache key


@dataclass(frozen=True)
class PathSpec:
    name: str
    type: str
    frames: int = _field(lo=1)
    params: tuple[tuple[str, Any], ...] = _field((), table=True)
    # Where its preset came from (recorded in the resolved study.toml); not part of equality.
    origin: str = field(default="", compare=False, metadata={"toml": False})


@dataclass(frozen=True)
class Variant:
    """One point of a pipeline entry's sweep: what a row's ``pipeline`` and ``params`` hold."""

    label: str
    type: str
    params: tuple[tuple[str, Any], ...]

    @property
    def params_json(self) -> str:
        return json.dumps(dict(self.params), sort_keys=True, separators=(",", ":"))


@dataclass(frozen=True)
class MatchSpec:
    """A point of a pipeline entry's one-key sweep found by bisection (``study.matching``): the
    swept value at which the mean over a sequence's scored frames of ``on`` (a metric, a count
    or ``time_ms``) equals that of the pipeline labelled ``against``, within ``tolerance`` (in
    ``on``'s units; 0: as close as ``probes`` renders get). Its rows carry ``label``. A target
    the sweep does not reach is refused (``outside = "refuse"``) or, with ``"nearest"``, met
    by the sweep's point closest to it, its rows saying ``match_reached = false``."""

    label: str
    against: str
    on: str
    tolerance: float = 0.0
    probes: int = _field(24, lo=1)
    outside: str = "refuse"


@dataclass(frozen=True)
class PipelineSpec:
    label: str
    type: str
    params: tuple[tuple[str, Any], ...] = _field((), table=True)
    sweep: tuple[tuple[str, tuple], ...] = _field((), table=True)
    sweep_mode: str = "cartesian"
    variants: tuple[Variant, ...] = _field((), toml=False)
    origin: str = field(default="", compare=False, metadata={"toml": False})
    # Points of the sweep matched to another pipeline's measurement ([[pipelines.match]]).
    match: tuple[MatchSpec, ...] = _field((), toml=False)


@dataclass(frozen=True)
class ReferenceSpec:
    pipeline: str = "reference"
    params: tuple[tuple[str, Any], ...] = _field((), table=True)
    # Also render each reference frame at twice its samples per side and warn where the two
    # differ by less than min_margin_db more than the best pipeline does (5x the reference cost).
    check_convergence: bool = False
    min_margin_db: float = 10.0


@dataclass(frozen=True)
class TimingSpec:
    warmup: int = _field(1, lo=0)
    repeats: int = _field(3, lo=1)
    # Also compile and time each variant's single-frame program (time_ms_single beside the
    # per-frame time in the sequence); false compiles one program fewer per variant.
    single_frame: bool = True
    # What the timed programs return. "images": the images alone, so that XLA drops what only
    # the counts and views need and a time is the architecture's work; the rows' counts come
    # from a second, instrumented program. "all": the instrumented program is timed itself
    # (one program fewer to compile; the times then include the counts and views).
    outputs: str = "images"


@dataclass(frozen=True)
class Study:
    file: str = _field(toml=False)
    name: str = _field("")
    description: str = _field("", empty=True)
    resolution: tuple[int, int] = (320, 180)  # (width, height)
    scenes: tuple[SceneSpec, ...] = _field((), required=True)
    paths: tuple[PathSpec, ...] = None
    pipelines: tuple[PipelineSpec, ...] = _field((), required=True)
    reference: ReferenceSpec = _field(None, table=True)
    metrics: tuple[str, ...] = DEFAULT_METRICS
    figures: tuple[str, ...] = FIGURES
    save_frames: tuple[int, ...] = (0,)
    timing: TimingSpec = _field(None, table=True)
    # Frames rendered before the scored ones of every path (the path runs that much longer
    # and its first frames are dropped), so that temporal pipelines start with a warm history.
    warmup_frames: int = _field(0, lo=0)

    @property
    def variants(self) -> tuple[Variant, ...]:
        return tuple(v for p in self.pipelines for v in p.variants)

    def with_overrides(self, *, frames: int | None = None, resolution=None) -> Study:
        """The study with every path's frame count and/or the resolution replaced (CLI)."""
        s = self
        if frames is not None:
            if not isinstance(frames, int) or frames < 1:
                raise UserError(f"--frames: expected a positive integer, got {frames!r}")
            s = dataclasses.replace(
                s, paths=tuple(dataclasses.replace(p, frames=frames) for p in s.paths)
            )
        if resolution is not None:
            s = dataclasses.replace(s, resolution=parse_resolution(resolution, "--resolution"))
            if "mssim" in s.metrics and min(s.resolution) < SSIM_MIN_SIDE:
                raise UserError(f"--resolution: MSSIM needs at least {SSIM_MIN_SIDE}x"
                                f"{SSIM_MIN_SIDE} pixels; the study asks for mssim")
        return s


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {v!r} as TOML")


def _fields_toml(spec, **extra) -> list[str]:
    """``key = value`` lines of a spec's TOML fields (tables of pairs written as tables)."""
    out = [f"{k} = {_toml_value(v)}" for k, v in extra.items()]
    for f in dataclasses.fields(spec):
        v = getattr(spec, f.name)
        if f.metadata.get("toml", True) and not dataclasses.is_dataclass(v) and not (
                v and isinstance(v, tuple) and dataclasses.is_dataclass(v[0])):
            out.append(f"{f.name} = {_toml_value(dict(v) if f.metadata.get('table') else v)}")
    return out


def to_toml(study: Study) -> str:
    """The study fully resolved (presets expanded, CLI overrides applied) as a study file that
    ``load_study`` reads back to an equal Study."""
    lines = [f"# resolved from {study.file}", *_fields_toml(study)]
    for section in ("reference", "timing"):
        lines += ["", f"[{section}]", *_fields_toml(getattr(study, section))]
    for section in ("scenes", "paths", "pipelines"):
        for spec in getattr(study, section):
            extra = {"name": spec.source} if section == "scenes" else {}
            origin = [f"# {spec.origin}"] if getattr(spec, "origin", "") else []
            lines += ["", f"[[{section}]]", *origin, *_fields_toml(spec, **extra)]
            for m in getattr(spec, "match", ()):
                lines += ["", "[[pipelines.match]]", *_fields_toml(m)]
    return "\n".join(lines) + "\n"
