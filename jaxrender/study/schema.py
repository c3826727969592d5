"""Study files: TOML read once with tomllib, validated into frozen objects.

Every error names the file and the key path (``studies/x.toml: pipelines[2].sweep.threshold:
expected a non-empty list``). A study composes reusable configs: scenes are built-in names or
files under ``configs/scenes/``, camera paths may be presets from ``configs/paths/`` and
pipelines presets from ``configs/pipelines/``. Sweeps are explicit lists, combined as a
cartesian product or zipped. See ``studies/quickstart.toml`` for a commented example.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jaxrender.metrics import METRICS
from jaxrender.scene.camera_path import PATH_TYPES, REQUIRED
from jaxrender.study import backend
from jaxrender.study.errors import StudyError, UserError

FIGURES = (
    "image_grid",
    "pareto_time",
    "pareto_count",
    "temporal",
    "dacs_decisions",
    "object_space_marking",
    "visbuffer_waves",
    "summary_table",
)
MAX_SIDE = 8192
SSIM_MIN_SIDE = 11  # the 11-tap Gaussian window of Wang et al.

_TOP_KEYS = {
    "name", "description", "resolution", "frames", "metrics", "figures", "save_frames",
    "scenes", "paths", "pipelines", "reference", "timing", "warmup_frames",
}
_SCENE_KEYS = {"name", "label", "params"}
_PATH_KEYS = {"name", "preset", "type", "frames", "params", "description"}
_PIPE_KEYS = {"type", "label", "preset", "params", "sweep", "sweep_mode", "description"}
_PRESET_PIPE_KEYS = {"type", "params", "sweep", "sweep_mode", "description"}
_REF_KEYS = {"pipeline", "params", "check_convergence", "min_margin_db"}
_TIMING_KEYS = {"warmup", "repeats", "single_frame"}


# ------------------------------------------------------------------ the validated objects


@dataclass(frozen=True)
class SceneSpec:
    label: str  # the name rows use
    source: str  # built-in scene name, or an absolute path to a scene TOML file
    params: tuple[tuple[str, Any], ...] = ()
    file_hash: str = ""  # sha256 of the scene file (empty for built-ins), for the cache key


@dataclass(frozen=True)
class PathSpec:
    name: str
    type: str
    frames: int
    params: tuple[tuple[str, Any], ...] = ()


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
class PipelineSpec:
    label: str
    type: str
    params: tuple[tuple[str, Any], ...]
    sweep: tuple[tuple[str, tuple], ...]
    sweep_mode: str
    variants: tuple[Variant, ...]


@dataclass(frozen=True)
class ReferenceSpec:
    pipeline: str = "reference"
    params: tuple[tuple[str, Any], ...] = ()
    check_convergence: bool = True
    min_margin_db: float = 10.0


@dataclass(frozen=True)
class TimingSpec:
    warmup: int = 1
    repeats: int = 3
    # Also compile and time each variant's single-frame program (time_ms_single beside the
    # per-frame time in the sequence); false compiles one program per variant, not two.
    single_frame: bool = True


@dataclass(frozen=True)
class Study:
    file: str
    name: str
    description: str
    resolution: tuple[int, int]  # (width, height)
    scenes: tuple[SceneSpec, ...]
    paths: tuple[PathSpec, ...]
    pipelines: tuple[PipelineSpec, ...]
    reference: ReferenceSpec
    metrics: tuple[str, ...]
    figures: tuple[str, ...]
    save_frames: tuple[int, ...]
    timing: TimingSpec
    # Frames rendered before the scored ones of every path (the path runs that much longer
    # and its first frames are dropped), so that temporal pipelines start with a warm history.
    warmup_frames: int = 0

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


# ------------------------------------------------------------------ helpers


def parse_resolution(value, where: str = "resolution") -> tuple[int, int]:
    """'WxH' or [W, H] -> (W, H); UserError naming ``where`` otherwise."""
    msg = f"{where}: expected 'WxH' or [width, height] with integers in 1..{MAX_SIDE}"
    if isinstance(value, str):
        parts = value.lower().split("x")
        if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
            raise UserError(f"{msg}, got {value!r}")
        w, h = (int(p) for p in parts)
    elif isinstance(value, (list, tuple)) and len(value) == 2:
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            raise UserError(f"{msg}, got {value!r}")
        w, h = value
    else:
        raise UserError(f"{msg}, got {value!r}")
    if not (1 <= w <= MAX_SIDE and 1 <= h <= MAX_SIDE):
        raise UserError(f"{msg}, got {w}x{h}")
    return int(w), int(h)


def find_config_root(start: Path) -> Path:
    """The nearest directory at or above ``start`` holding ``configs/``, else the cwd."""
    for d in [start, *start.parents]:
        if (d / "configs").is_dir():
            return d
    return Path.cwd()


def _type_name(v) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


class _Checker:
    """Small typed accessors that raise StudyError naming the file and the key path."""

    def __init__(self, file: str):
        self.file = file

    def fail(self, path: str, msg: str):
        raise StudyError(self.file, path, msg)

    def table(self, v, path) -> dict:
        if not isinstance(v, dict):
            self.fail(path, f"expected a table, got {_type_name(v)}")
        return v

    def keys(self, d: dict, path: str, allowed: set, required=()):
        for k in d:
            if k not in allowed:
                where = f"{path}.{k}" if path else k
                self.fail(where, f"unknown key; allowed keys: {', '.join(sorted(allowed))}")
        for k in required:
            if k not in d:
                self.fail(path or "(top level)", f"missing required key {k!r}")

    def str_(self, v, path) -> str:
        if not isinstance(v, str) or not v:
            self.fail(path, f"expected a non-empty string, got {_type_name(v)}")
        return v

    def int_(self, v, path, lo=None) -> int:
        if not isinstance(v, int) or isinstance(v, bool):
            self.fail(path, f"expected an integer, got {_type_name(v)}")
        if lo is not None and v < lo:
            self.fail(path, f"expected an integer >= {lo}, got {v}")
        return v

    def num(self, v, path) -> float:
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            self.fail(path, f"expected a finite number, got {v!r}")
        return float(v)

    def bool_(self, v, path) -> bool:
        if not isinstance(v, bool):
            self.fail(path, f"expected true or false, got {_type_name(v)}")
        return v

    def list_(self, v, path, nonempty=True) -> list:
        if not isinstance(v, list):
            self.fail(path, f"expected a list, got {_type_name(v)}")
        if nonempty and not v:
            self.fail(path, "expected a non-empty list")
        return v

    def names(self, v, path, known) -> tuple[str, ...]:
        out = []
        for i, n in enumerate(self.list_(v, path)):
            n = self.str_(n, f"{path}[{i}]")
            if n not in known:
                self.fail(f"{path}[{i}]", f"unknown name {n!r}; known: {', '.join(known)}")
            if n in out:
                self.fail(f"{path}[{i}]", f"{n!r} is listed twice")
            out.append(n)
        return tuple(out)


def _read_toml(path: Path, shown: str) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise StudyError(shown, "", "no such file") from None
    except tomllib.TOMLDecodeError as e:
        raise StudyError(shown, "", f"invalid TOML: {e}") from None


def _rel(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


# ------------------------------------------------------------------ parameter checking


def _expected_kind(default):
    if isinstance(default, bool):
        return bool
    if isinstance(default, int):
        return int
    if isinstance(default, float):
        return float
    if isinstance(default, str):
        return str
    if isinstance(default, tuple):
        return tuple
    return None


def check_param(ck: _Checker, path: str, value, default, has_default: bool):
    """``value`` from TOML checked against the config field's default; returns the value in
    the field's type (lists become tuples, integers become floats for float fields)."""
    if isinstance(value, dict):
        ck.fail(path, "expected a value, got a table")
    kind = _expected_kind(default) if has_default else None
    if kind is None:
        return tuple(value) if isinstance(value, list) else value
    if kind is bool:
        return ck.bool_(value, path)
    if kind is int:
        return ck.int_(value, path)
    if kind is float:
        return ck.num(value, path)
    if kind is str:
        return ck.str_(value, path)
    if kind is tuple:
        if not isinstance(value, list):
            ck.fail(path, f"expected a list, got {_type_name(value)}")
        return tuple(value)
    return value


def check_params(ck: _Checker, path: str, ptype: str, params: dict, resolution) -> dict:
    """Parameters of pipeline ``ptype`` checked by name and type against its config class."""
    pipe = backend.pipeline(ptype)
    fields = {f.name: f for f in dataclasses.fields(pipe.config_cls)}
    out = {}
    for k, v in params.items():
        where = f"{path}.{k}" if path else k
        if k in ("width", "height"):
            ck.fail(where, "the resolution is set for the whole study (`resolution`)")
        if k not in fields:
            known = ", ".join(sorted(f for f in fields if f not in ("width", "height")))
            ck.fail(where, f"pipeline {ptype!r} has no parameter {k!r}; "
                    f"its parameters are: {known or '(none)'}")
        f = fields[k]
        has_default = f.default is not dataclasses.MISSING
        out[k] = check_param(ck, where, v, f.default if has_default else None, has_default)
    try:
        backend.make_config(ptype, resolution[0], resolution[1], out)
    except (TypeError, ValueError, KeyError) as e:
        ck.fail(path, f"pipeline {ptype!r} rejects these parameters: {e}")
    return out


# ------------------------------------------------------------------ sections


def _scenes(ck: _Checker, raw, root: Path, study_dir: Path) -> tuple[SceneSpec, ...]:
    items = ck.list_(raw, "scenes")
    builtins = None
    out: list[SceneSpec] = []
    for i, item in enumerate(items):
        path = f"scenes[{i}]"
        if isinstance(item, str):
            item = {"name": item}
        ck.table(item, path)
        ck.keys(item, path, _SCENE_KEYS, required=("name",))
        name = ck.str_(item["name"], f"{path}.name")
        label = ck.str_(item.get("label", Path(name).stem), f"{path}.label")
        params = dict(ck.table(item.get("params", {}), f"{path}.params"))
        for k, v in params.items():
            if isinstance(v, (dict, list)) and not (isinstance(v, list) and v):
                ck.fail(f"{path}.params.{k}", f"expected a value, got {_type_name(v)}")
        file = None
        if name.endswith(".toml") or "/" in name:
            for cand in (study_dir / name, root / name):
                if cand.is_file():
                    file = cand.resolve()
                    break
            if file is None:
                ck.fail(f"{path}.name", f"scene file {name!r} not found")
        elif (root / "configs" / "scenes" / f"{name}.toml").is_file():
            file = (root / "configs" / "scenes" / f"{name}.toml").resolve()
        else:
            if builtins is None:
                builtins = backend.builtin_scene_names()
            if name not in builtins:
                files = sorted(p.stem for p in (root / "configs" / "scenes").glob("*.toml"))
                ck.fail(f"{path}.name", f"unknown scene {name!r}; built-in scenes: "
                        f"{', '.join(builtins) or '(none)'}; scene files in configs/scenes: "
                        f"{', '.join(files) or '(none)'}")
        if file is None:
            sizes = backend.scene_params(name)
            if sizes is not None:
                for k, v in list(params.items()):
                    if k not in sizes:
                        ck.fail(f"{path}.params.{k}", f"scene {name!r} has no size parameter "
                                f"{k!r}; its parameters are: {', '.join(sizes) or '(none)'}")
                    params[k] = check_param(ck, f"{path}.params.{k}", v, sizes[k], True)
        elif params:
            ck.fail(f"{path}.params", "size parameters apply to built-in scenes only")
        if any(s.label == label for s in out):
            ck.fail(f"{path}.label", f"scene label {label!r} is used twice; set `label`")
        frozen = tuple(sorted((k, tuple(v) if isinstance(v, list) else v)
                              for k, v in params.items()))
        digest = hashlib.sha256(file.read_bytes()).hexdigest() if file else ""
        out.append(SceneSpec(label, str(file) if file else name, frozen, digest))
    return tuple(out)


def _paths(ck: _Checker, raw, root: Path, default_frames: int) -> tuple[PathSpec, ...]:
    if raw is None:
        return (PathSpec("static", "static", default_frames),)
    items = ck.list_(raw, "paths")
    known = list(PATH_TYPES)
    out: list[PathSpec] = []
    for i, item in enumerate(items):
        path = f"paths[{i}]"
        if isinstance(item, str):
            item = {"preset": item}
        ck.table(item, path)
        ck.keys(item, path, _PATH_KEYS)
        merged: dict = {}
        if "preset" in item:
            preset = ck.str_(item["preset"], f"{path}.preset")
            pfile = root / "configs" / "paths" / f"{preset}.toml"
            if not pfile.is_file():
                avail = sorted(p.stem for p in (root / "configs" / "paths").glob("*.toml"))
                ck.fail(f"{path}.preset", f"no camera path preset {preset!r} in configs/paths; "
                        f"available: {', '.join(avail) or '(none)'}")
            pck = _Checker(_rel(pfile))
            pdata = _read_toml(pfile, pck.file)
            pck.keys(pdata, "", _PATH_KEYS - {"preset", "name"})
            merged.update(pdata)
            merged.setdefault("name", preset)
            merged["params"] = {**pdata.get("params", {}), **item.get("params", {})}
        merged.update({k: v for k, v in item.items() if k not in ("preset", "params")})
        merged.setdefault("params", item.get("params", {}))
        if "type" not in merged:
            ck.fail(path, "missing required key 'type' (or a 'preset' that sets it)")
        ptype = ck.str_(merged["type"], f"{path}.type")
        if ptype not in known:
            ck.fail(f"{path}.type", f"unknown camera path type {ptype!r}; known: "
                    f"{', '.join(known)}")
        name = ck.str_(merged.get("name", ptype), f"{path}.name")
        frames = ck.int_(merged.get("frames", default_frames), f"{path}.frames", lo=1)
        params = dict(ck.table(merged["params"], f"{path}.params"))
        for k, v in params.items():
            if isinstance(v, dict):
                ck.fail(f"{path}.params.{k}", "expected a value, got a table")
        spec = PATH_TYPES[ptype].params
        if spec is not None:
            for k, v in params.items():
                if k not in spec:
                    ck.fail(f"{path}.params.{k}", f"camera path {ptype!r} has no parameter "
                            f"{k!r}; its parameters are: {', '.join(spec) or '(none)'}")
                kind = spec[k].kind
                if kind is float:
                    params[k] = ck.num(v, f"{path}.params.{k}")
                elif kind is str:
                    params[k] = ck.str_(v, f"{path}.params.{k}")
                elif kind is tuple and not (isinstance(v, list) and len(v) == 3 and all(
                        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
                    ck.fail(f"{path}.params.{k}", "expected a list of 3 numbers")
            for k, p in spec.items():
                if p.default is REQUIRED and k not in params:
                    ck.fail(f"{path}.params", f"camera path {ptype!r} needs the parameter {k!r}")
        if any(p.name == name for p in out):
            ck.fail(f"{path}.name", f"camera path name {name!r} is used twice")
        frozen = tuple(sorted((k, tuple(v) if isinstance(v, list) else v)
                              for k, v in params.items()))
        out.append(PathSpec(name, ptype, frames, frozen))
    return tuple(out)


def _variants(ck, path, label, ptype, fixed: dict, sweep: dict, mode: str) -> tuple:
    names = list(sweep)
    if not names:
        combos = [()]
    elif mode == "zip":
        lengths = {k: len(v) for k, v in sweep.items()}
        if len(set(lengths.values())) > 1:
            desc = ", ".join(f"{k} has {n}" for k, n in lengths.items())
            ck.fail(f"{path}.sweep", f"zip needs lists of equal length; {desc}")
        combos = list(zip(*sweep.values()))
    else:
        combos = list(itertools.product(*sweep.values()))
    out = []
    for combo in combos:
        params = {**fixed, **dict(zip(names, combo))}
        out.append(Variant(label, ptype, tuple(sorted(params.items()))))
    return tuple(out)


def _pipelines(ck: _Checker, raw, root: Path, resolution) -> tuple[PipelineSpec, ...]:
    items = ck.list_(raw, "pipelines")
    out: list[PipelineSpec] = []
    for i, item in enumerate(items):
        path = f"pipelines[{i}]"
        ck.table(item, path)
        ck.keys(item, path, _PIPE_KEYS)
        merged: dict = {}
        if "preset" in item:
            preset = ck.str_(item["preset"], f"{path}.preset")
            pfile = root / "configs" / "pipelines" / f"{preset}.toml"
            if not pfile.is_file():
                avail = sorted(p.stem for p in (root / "configs" / "pipelines").glob("*.toml"))
                ck.fail(f"{path}.preset", f"no pipeline preset {preset!r} in configs/pipelines; "
                        f"available: {', '.join(avail) or '(none)'}")
            pck = _Checker(_rel(pfile))
            pdata = _read_toml(pfile, pck.file)
            pck.keys(pdata, "", _PRESET_PIPE_KEYS, required=("type",))
            pck.table(pdata.get("params", {}), "params")
            pck.table(pdata.get("sweep", {}), "sweep")
            if "type" in item and item["type"] != pdata["type"]:
                ck.fail(f"{path}.type", f"preset {preset!r} is a {pdata['type']!r} pipeline, "
                        f"not {item['type']!r}")
            merged = dict(pdata)
            merged.setdefault("label", preset)
        for k, v in item.items():
            if k in ("params", "sweep") and k in merged:
                merged[k] = {**merged[k], **ck.table(v, f"{path}.{k}")}
            elif k != "preset":
                merged[k] = v
        if "type" not in merged:
            ck.fail(path, "missing required key 'type' (or a 'preset' that sets it)")
        ptype = ck.str_(merged["type"], f"{path}.type")
        if ptype not in backend.registered_pipelines():
            known = ", ".join(backend.registered_pipelines()) or "(none yet)"
            ck.fail(f"{path}.type", f"pipeline {ptype!r} is not registered; registered: {known}")
        label = ck.str_(merged.get("label", ptype), f"{path}.label")
        if any(p.label == label for p in out):
            ck.fail(f"{path}.label", f"pipeline label {label!r} is used twice; give each entry "
                    "a distinct `label`")
        mode = ck.str_(merged.get("sweep_mode", "cartesian"), f"{path}.sweep_mode")
        if mode not in ("cartesian", "zip"):
            ck.fail(f"{path}.sweep_mode", f"expected 'cartesian' or 'zip', got {mode!r}")
        fixed = check_params(ck, f"{path}.params", ptype,
                             ck.table(merged.get("params", {}), f"{path}.params"), resolution)
        sweep_raw = ck.table(merged.get("sweep", {}), f"{path}.sweep")
        sweep: dict = {}
        for k, values in sweep_raw.items():
            if k in fixed:
                ck.fail(f"{path}.sweep.{k}", f"{k!r} is both a fixed parameter and swept")
            if not isinstance(values, list) or not values:
                ck.fail(f"{path}.sweep.{k}", "expected a non-empty list of values to sweep")
            checked = [check_params(ck, f"{path}.sweep", ptype, {k: v}, resolution)[k]
                       for v in values]
            sweep[k] = tuple(checked)
            if len(set(map(repr, checked))) != len(checked):
                ck.fail(f"{path}.sweep.{k}", "a swept value is listed twice")
        variants = _variants(ck, path, label, ptype, fixed, sweep, mode)
        for v in variants:
            try:
                backend.make_config(ptype, resolution[0], resolution[1], dict(v.params))
            except (TypeError, ValueError, KeyError) as e:
                ck.fail(f"{path}.sweep", f"pipeline {ptype!r} rejects {v.params_json}: {e}")
        out.append(PipelineSpec(label, ptype, tuple(sorted(fixed.items())),
                                tuple(sweep.items()), mode, variants))
    return tuple(out)


def _reference(ck: _Checker, raw, resolution) -> ReferenceSpec:
    raw = ck.table(raw if raw is not None else {}, "reference")
    ck.keys(raw, "reference", _REF_KEYS)
    pipe = ck.str_(raw.get("pipeline", "reference"), "reference.pipeline")
    if pipe not in backend.registered_pipelines():
        known = ", ".join(backend.registered_pipelines()) or "(none yet)"
        ck.fail("reference.pipeline", f"pipeline {pipe!r} is not registered; registered: {known}")
    params = check_params(ck, "reference.params", pipe,
                          ck.table(raw.get("params", {}), "reference.params"), resolution)
    return ReferenceSpec(
        pipe,
        tuple(sorted(params.items())),
        ck.bool_(raw.get("check_convergence", True), "reference.check_convergence"),
        ck.num(raw.get("min_margin_db", 10.0), "reference.min_margin_db"),
    )


# ------------------------------------------------------------------ entry points


def load_study(file, *, config_root: Path | None = None) -> Study:
    """Read and validate a study file; StudyError names the file and key on any mistake."""
    p = Path(file)
    shown = str(file)
    data = _read_toml(p, shown)
    return parse_study(data, shown, study_dir=p.resolve().parent, config_root=config_root)


def parse_study(data: dict, file: str, *, study_dir: Path, config_root: Path | None = None):
    ck = _Checker(file)
    root = config_root or find_config_root(study_dir)
    ck.keys(data, "", _TOP_KEYS, required=("scenes", "pipelines"))
    name = ck.str_(data.get("name", Path(file).stem), "name")
    if not all(c.isalnum() or c in "-_." for c in name):
        ck.fail("name", f"use letters, digits, '-', '_' or '.', got {name!r}")
    description = data.get("description", "")
    if not isinstance(description, str):
        ck.fail("description", f"expected a string, got {_type_name(description)}")
    try:
        resolution = parse_resolution(data.get("resolution", [320, 180]), "resolution")
    except UserError as e:
        raise StudyError(file, "resolution", str(e).split(": ", 1)[1]) from None
    frames = ck.int_(data.get("frames", 1), "frames", lo=1)
    metrics = ck.names(data.get("metrics", list(METRICS)), "metrics", tuple(METRICS))
    if "mssim" in metrics and min(resolution) < SSIM_MIN_SIDE:
        ck.fail("resolution", f"MSSIM needs images of at least {SSIM_MIN_SIDE}x{SSIM_MIN_SIDE} "
                f"pixels (its window); drop 'mssim' from metrics or raise the resolution")
    figures = ck.names(data.get("figures", list(FIGURES)), "figures", FIGURES)
    save = ck.list_(data.get("save_frames", [0]), "save_frames", nonempty=False)
    save_frames = tuple(sorted({ck.int_(v, f"save_frames[{i}]", lo=0)
                                for i, v in enumerate(save)}))
    timing_raw = ck.table(data.get("timing", {}), "timing")
    ck.keys(timing_raw, "timing", _TIMING_KEYS)
    timing = TimingSpec(ck.int_(timing_raw.get("warmup", 1), "timing.warmup", lo=0),
                        ck.int_(timing_raw.get("repeats", 3), "timing.repeats", lo=1),
                        ck.bool_(timing_raw.get("single_frame", True), "timing.single_frame"))
    scenes = _scenes(ck, data["scenes"], root, study_dir)
    paths = _paths(ck, data.get("paths"), root, frames)
    pipelines = _pipelines(ck, data["pipelines"], root, resolution)
    reference = _reference(ck, data.get("reference"), resolution)
    warmup_frames = ck.int_(data.get("warmup_frames", 0), "warmup_frames", lo=0)
    return Study(file, name, description, resolution, scenes, paths, pipelines, reference,
                 metrics, figures, save_frames, timing, warmup_frames)


# ------------------------------------------------------------------ the resolved config


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


def to_toml(study: Study) -> str:
    """The study fully resolved (presets expanded, CLI overrides applied) as a study file that
    ``load_study`` reads back to an equal Study."""
    w, h = study.resolution
    lines = [
        f"# resolved from {study.file}",
        f"name = {_toml_value(study.name)}",
        f"description = {_toml_value(study.description)}",
        f"resolution = [{w}, {h}]",
        f"metrics = {_toml_value(study.metrics)}",
        f"figures = {_toml_value(study.figures)}",
        f"save_frames = {_toml_value(study.save_frames)}",
        f"warmup_frames = {study.warmup_frames}",
        "",
        "[reference]",
        f"pipeline = {_toml_value(study.reference.pipeline)}",
        f"params = {_toml_value(dict(study.reference.params))}",
        f"check_convergence = {_toml_value(study.reference.check_convergence)}",
        f"min_margin_db = {_toml_value(study.reference.min_margin_db)}",
        "",
        "[timing]",
        f"warmup = {study.timing.warmup}",
        f"repeats = {study.timing.repeats}",
        f"single_frame = {_toml_value(study.timing.single_frame)}",
    ]
    for s in study.scenes:
        lines += ["", "[[scenes]]", f"name = {_toml_value(s.source)}",
                  f"label = {_toml_value(s.label)}", f"params = {_toml_value(dict(s.params))}"]
    for p in study.paths:
        lines += ["", "[[paths]]", f"name = {_toml_value(p.name)}", f"type = {_toml_value(p.type)}",
                  f"frames = {p.frames}", f"params = {_toml_value(dict(p.params))}"]
    for p in study.pipelines:
        lines += ["", "[[pipelines]]", f"type = {_toml_value(p.type)}",
                  f"label = {_toml_value(p.label)}", f"params = {_toml_value(dict(p.params))}",
                  f"sweep = {_toml_value(dict(p.sweep))}",
                  f"sweep_mode = {_toml_value(p.sweep_mode)}"]
    return "\n".join(lines) + "\n"
