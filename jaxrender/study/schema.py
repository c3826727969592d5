"""Study files: TOML read once with tomllib, validated into frozen objects.

Every error names the file and the key path (``studies/x.toml: pipelines[2].sweep.threshold:
expected a non-empty list``). A study composes reusable configs: scenes are built-in names or
scene files, camera paths may be presets and pipelines presets, each found by name in a local
``configs/{scenes,paths,pipelines}/`` (beside the study, or ``--configs DIR``) and then among
the built-ins (``jaxrender.catalog``). Sweeps are explicit lists, combined as a cartesian
product or zipped. Every pipeline entry also takes ``shader_cost`` (an integer >= 0, in
``params`` or ``sweep``): the scene's shader cost for its variants, in extra light layers
(``jaxrender.study.shader_cost``). See ``studies/quickstart.toml`` for a commented example.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
from pathlib import Path

from jaxrender import catalog
from jaxrender.errors import StudyError, UserError
from jaxrender.metrics import DEFAULT_METRICS, METRICS
from jaxrender.parsing import parse_resolution
from jaxrender.scene.camera_path import PATH_TYPES, REQUIRED, overridden_message
from jaxrender.study import backend, matching, shader_cost
from jaxrender.study.specs import (FIGURES, SSIM_MIN_SIDE, TIMED_OUTPUTS, PathSpec,
                                   PipelineSpec, ReferenceSpec, SceneSpec, Study, TimingSpec,
                                   Variant)
from jaxrender.study.tables import (Checker, type_name, key_path, read_table, read_toml,
                                    shown_path)


def _frozen(params: dict) -> tuple:
    return tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in params.items()))


def with_preset(ck: Checker, item: dict, path: str, local, cls, kind: str,
                name_key: str, fixed=()) -> tuple[dict, str]:
    """A study entry merged over its preset ``<kind>/<preset>.toml`` (local configs first,
    then the built-ins; the entry's ``params`` and ``sweep`` tables merged key by key over the
    preset's; ``name_key`` defaults to the preset's name), and where the preset came from
    ("" without one). The preset's own mistakes are named in its file; a key in ``fixed`` may
    not differ between the entry and its preset."""
    if "preset" not in item:
        return dict(item), ""
    preset = ck.str_(item["preset"], f"{path}.preset")
    entry = catalog.find(kind, preset, local)
    what = "camera path" if kind == "paths" else "pipeline"
    if entry is None:
        ck.fail(f"{path}.preset", f"no {what} preset {preset!r}; available: "
                f"{catalog.available(kind, local)}")
    pfile = entry.path
    pck = Checker(shown_path(pfile))
    merged = read_toml(pfile, pck.file)
    pck.keys(merged, "", _keys(cls, kind) - {"preset", name_key}, required=fixed)
    for k in ("params", "sweep"):
        if k in merged:
            pck.table(merged[k], k)
    for k in fixed:
        if k in item and item[k] != merged[k]:
            ck.fail(f"{path}.{k}", f"preset {preset!r} is a {merged[k]!r} {what}, "
                    f"not {item[k]!r}")
    merged.setdefault(name_key, preset)
    for k, v in item.items():
        if k in ("params", "sweep"):
            merged[k] = {**merged.get(k, {}), **ck.table(v, f"{path}.{k}")}
        elif k != "preset":
            merged[k] = v
    return merged, f"preset {preset!r}: {entry.describe()}"


# ------------------------------------------------------------------ parameter checking


def check_params(ck: Checker, path: str, ptype: str, params: dict, resolution) -> dict:
    """Parameters of pipeline ``ptype`` checked by name and type against its config class
    (and ``shader_cost``, which every pipeline entry takes: ``study.shader_cost``); returns
    them in the fields' types (lists become tuples, integers floats for floats)."""
    pipe = backend.pipeline(ptype)
    fields = {f.name: f for f in dataclasses.fields(pipe.config_cls)}
    out = {}
    for k, v in params.items():
        where = key_path(path, k)
        if k in ("width", "height"):
            ck.fail(where, "the resolution is set for the whole study (`resolution`)")
        if k == shader_cost.KEY:
            out[k] = ck.int_(v, where, lo=0)
            continue
        if k not in fields:
            known = ", ".join(sorted(f for f in fields if f not in ("width", "height")))
            ck.fail(where, f"pipeline {ptype!r} has no parameter {k!r}; "
                    f"its parameters are: {known or '(none)'} (and {shader_cost.KEY})")
        out[k] = _check_value(ck, where, v, fields[k].default)
    try:
        backend.make_config(ptype, resolution[0], resolution[1], shader_cost.split(out)[0])
    except (TypeError, ValueError, KeyError) as e:
        ck.fail(path, f"pipeline {ptype!r} rejects these parameters: {e}")
    return out


def _check_value(ck: Checker, path: str, value, default):
    """A parameter checked against the type of its default (none: any value)."""
    if isinstance(value, dict):
        ck.fail(path, "expected a value, got a table")
    if isinstance(default, tuple):
        return tuple(ck.list_(value, path, nonempty=False))
    if isinstance(default, (bool, int, float, str)):
        return ck.value(value, path, type(default))
    return tuple(value) if isinstance(value, list) else value


# ------------------------------------------------------------------ sections

_ENTRY_KEYS = {  # the keys a study's entries accept besides their spec's fields
    "scenes": ("name",),
    "paths": ("preset", "description"),
    "pipelines": ("preset", "description", "match"),
}


def _scene(ck: Checker, item, path: str, local, study_dir: Path) -> SceneSpec:
    if isinstance(item, str):
        item = {"name": item}
    d = read_table(ck, item, path, SceneSpec, extra=_ENTRY_KEYS["scenes"],
                   defaults={"label": None})
    if "name" not in d:
        ck.fail(path, "missing required key 'name'")
    name = ck.str_(d["name"], f"{path}.name")
    label = ck.str_(d["label"] or Path(name).stem, f"{path}.label")
    params = dict(d["params"])
    file = _scene_file(ck, name, path, local, study_dir)
    for k, v in params.items():
        if isinstance(v, (dict, list)) and not (isinstance(v, list) and v):
            ck.fail(f"{path}.params.{k}", f"expected a value, got {type_name(v)}")
    sizes = backend.scene_params(name) if file is None else None
    if sizes is not None:
        for k, v in params.items():
            if k not in sizes:
                ck.fail(f"{path}.params.{k}", f"scene {name!r} has no size parameter {k!r}; "
                        f"its parameters are: {', '.join(sizes) or '(none)'}")
            params[k] = _check_value(ck, f"{path}.params.{k}", v, sizes[k])
    elif file is not None and params:
        ck.fail(f"{path}.params", "size parameters apply to built-in scenes only")
    digest = hashlib.sha256(file.read_bytes()).hexdigest() if file else ""
    return SceneSpec(label, str(file) if file else name, _frozen(params), digest)


def _scene_file(ck: Checker, name: str, path: str, local, study_dir: Path):
    """The scene file ``name`` names (a path relative to the study or to a local configs
    folder's parent, or the stem of a scene file in a configs folder), or None for a built-in
    scene."""
    if name.endswith(".toml") or "/" in name:
        nearest = catalog.nearest_configs(study_dir)
        bases = [study_dir, *(Path(d).parent for d in local),
                 *([nearest.parent] if nearest else []), Path.cwd()]
        for cand in (b / name for b in bases):
            if cand.is_file():
                return cand.resolve()
        ck.fail(f"{path}.name", f"scene file {name!r} not found")
    entry = catalog.find("scenes", name, local)
    if entry is not None:
        return entry.path
    builtins = backend.builtin_scene_names()
    if name not in builtins:
        ck.fail(f"{path}.name", f"unknown scene {name!r}; built-in scenes: "
                f"{', '.join(builtins) or '(none)'}; scene files: "
                f"{catalog.available('scenes', local)}")
    return None


def _path(ck: Checker, item, path: str, local, default_frames: int) -> PathSpec:
    if isinstance(item, str):
        item = {"preset": item}
    ck.keys(ck.table(item, path), path, _keys(PathSpec, "paths"))
    merged, source = with_preset(ck, item, path, local, PathSpec, "paths", "name")
    d = read_table(ck, merged, path, PathSpec, extra=_ENTRY_KEYS["paths"],
                   defaults={"name": None, "frames": default_frames},
                   hint=" (or a 'preset' that sets it)")
    ptype = d["type"]
    if ptype not in PATH_TYPES:
        ck.fail(f"{path}.type", f"unknown camera path type {ptype!r}; known: "
                f"{', '.join(PATH_TYPES)}")
    name = ck.str_(d["name"] or ptype, f"{path}.name")
    params = d["params"]
    declared = PATH_TYPES[ptype].params
    for k, v in params.items():
        where = f"{path}.params.{k}"
        if k not in declared:
            ck.fail(where, f"camera path {ptype!r} has no parameter {k!r}; its parameters "
                    f"are: {', '.join(declared) or '(none)'}")
        if declared[k].kind is tuple:
            if not (isinstance(v, list) and len(v) == 3 and all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)):
                ck.fail(where, "expected a list of 3 numbers")
        else:
            params[k] = ck.value(v, where, declared[k].kind)
    for k, p in declared.items():
        if p.default is REQUIRED and k not in params:
            ck.fail(f"{path}.params", f"camera path {ptype!r} needs the parameter {k!r}")
    own = item.get("params", {})  # the entry's own, a table by now
    for k, by in PATH_TYPES[ptype].overridden:
        if k in params and by in params:
            if by in own and k not in own:  # the entry's key replaces what its preset set
                del params[k]
            else:
                ck.fail(f"{path}.params.{k}", overridden_message(ptype, k, by))
    return PathSpec(name, ptype, d["frames"], _frozen(params), source)


def _keys(cls, kind: str) -> set:
    return {f.name for f in dataclasses.fields(cls) if f.metadata.get("toml", True)} | set(
        _ENTRY_KEYS[kind])


def _variants(ck, path, label, ptype, fixed: dict, sweep: dict, mode: str) -> tuple:
    if mode == "zip":
        lengths = {k: len(v) for k, v in sweep.items()}
        if len(set(lengths.values())) > 1:
            desc = ", ".join(f"{k} has {n}" for k, n in lengths.items())
            ck.fail(f"{path}.sweep", f"zip needs lists of equal length; {desc}")
        combos = list(zip(*sweep.values())) if sweep else [()]
    else:
        combos = list(itertools.product(*sweep.values()))
    return tuple(Variant(label, ptype, tuple(sorted({**fixed, **dict(zip(sweep, c))}.items())))
                 for c in combos)


def _pipeline_type(ck: Checker, ptype: str, where: str) -> str:
    if ptype not in backend.registered_pipelines():
        known = ", ".join(backend.registered_pipelines()) or "(none)"
        ck.fail(where, f"pipeline {ptype!r} is not registered; registered: {known}")
    return ptype


def _sweep(ck: Checker, path: str, ptype: str, raw: dict, fixed: dict, resolution) -> dict:
    sweep: dict = {}
    for k, values in raw.items():
        if k in fixed:
            ck.fail(f"{path}.sweep.{k}", f"{k!r} is both a fixed parameter and swept")
        if not isinstance(values, list) or not values:
            ck.fail(f"{path}.sweep.{k}", "expected a non-empty list of values to sweep")
        checked = [check_params(ck, f"{path}.sweep", ptype, {k: v}, resolution)[k]
                   for v in values]
        if len(set(map(repr, checked))) != len(checked):
            ck.fail(f"{path}.sweep.{k}", "a swept value is listed twice")
        sweep[k] = tuple(checked)
    return sweep


def _pipeline(ck: Checker, item, path: str, local, resolution) -> PipelineSpec:
    ck.keys(ck.table(item, path), path, _keys(PipelineSpec, "pipelines"))
    merged, source = with_preset(ck, item, path, local, PipelineSpec, "pipelines", "label",
                                 fixed=("type",))
    d = read_table(ck, merged, path, PipelineSpec, extra=_ENTRY_KEYS["pipelines"],
                   defaults={"label": None}, hint=" (or a 'preset' that sets it)")
    ptype = _pipeline_type(ck, d["type"], f"{path}.type")
    label = ck.str_(d["label"] or ptype, f"{path}.label")
    mode = d["sweep_mode"]
    if mode not in ("cartesian", "zip"):
        ck.fail(f"{path}.sweep_mode", f"expected 'cartesian' or 'zip', got {mode!r}")
    fixed = check_params(ck, f"{path}.params", ptype, dict(d["params"]), resolution)
    sweep = _sweep(ck, path, ptype, dict(d["sweep"]), fixed, resolution)
    variants = _variants(ck, path, label, ptype, fixed, sweep, mode)
    for v in variants:
        try:
            backend.make_config(ptype, resolution[0], resolution[1],
                                shader_cost.split(dict(v.params))[0])
        except (TypeError, ValueError, KeyError) as e:
            ck.fail(f"{path}.sweep", f"pipeline {ptype!r} rejects {v.params_json}: {e}")
    matches = matching.parse(ck, d.get("match"), path, label, ptype, sweep)
    return PipelineSpec(label, ptype, tuple(sorted(fixed.items())), tuple(sweep.items()),
                        mode, variants, source, matches)


def _reference(ck: Checker, raw, resolution) -> ReferenceSpec:
    d = read_table(ck, raw, "reference", ReferenceSpec)
    pipe = _pipeline_type(ck, d["pipeline"], "reference.pipeline")
    params = check_params(ck, "reference.params", pipe, dict(d["params"]), resolution)
    if shader_cost.KEY in params:
        ck.fail(f"reference.params.{shader_cost.KEY}", "the reference renders each scene with "
                "the scene's own shader (every variant is scored against it); set the shader "
                "cost in the pipeline entries")
    if d["check_convergence"]:
        # The check is the reference's own 2k render (its ``convergence`` parameter).
        fields = {f.name for f in dataclasses.fields(backend.pipeline(pipe).config_cls)}
        if "convergence" not in fields:
            ck.fail("reference.check_convergence", f"reference pipeline {pipe!r} has no "
                    f"'convergence' parameter to check its convergence with")
        if params.get("convergence") is False:
            ck.fail("reference.params.convergence", "check_convergence = true needs the "
                    "reference's convergence render; drop one of the two")
        params["convergence"] = True
    return ReferenceSpec(pipe, tuple(sorted(params.items())), d["check_convergence"],
                         d["min_margin_db"])


def _unique(ck: Checker, specs, attr: str, section: str, what: str, fix: str = ""):
    seen = set()
    for i, s in enumerate(specs):
        v = getattr(s, attr)
        if v in seen:
            ck.fail(f"{section}[{i}].{attr}", f"{what} {v!r} is used twice{fix}")
        seen.add(v)
    return tuple(specs)


# ------------------------------------------------------------------ entry points


def study_file(name_or_file) -> Path:
    """A study file's path: an existing file as given, else a bundled study of that name."""
    p = Path(name_or_file)
    if p.is_file() or p.suffix == ".toml" or len(p.parts) > 1:
        return p
    entry = catalog.find("studies", str(name_or_file))
    if entry is None:
        raise UserError(f"{name_or_file}: neither a study file nor a bundled study; bundled "
                        f"studies: {catalog.available('studies')}")
    return entry.path


def load_study(file, *, configs: Path | None = None) -> Study:
    """Read and validate a study file (or a bundled study, by name); StudyError names the
    file and key on any mistake. ``configs``: a local configs folder to use instead of the
    one found beside the study."""
    p = study_file(file)
    data = read_toml(p, str(p))
    return parse_study(data, str(p), study_dir=p.resolve().parent, configs=configs)


def parse_study(data: dict, file: str, *, study_dir: Path, configs: Path | None = None):
    ck = Checker(file)
    try:
        local = catalog.local_configs(study_dir, configs)
    except FileNotFoundError as e:
        raise UserError(f"--configs: {e}") from None
    d = read_table(ck, data, "", Study, extra={"frames": 1},
                   defaults={"name": Path(file).stem, "metrics": list(DEFAULT_METRICS),
                             "figures": list(FIGURES), "save_frames": [0]})
    if not all(c.isalnum() or c in "-_." for c in d["name"]):
        ck.fail("name", f"use letters, digits, '-', '_' or '.', got {d['name']!r}")
    try:
        resolution = parse_resolution(d["resolution"], "resolution")
    except UserError as e:
        raise StudyError(file, "resolution", str(e).split(": ", 1)[1]) from None
    frames = ck.int_(data.get("frames", 1), "frames", lo=1)
    metrics = ck.names(d["metrics"], "metrics", tuple(METRICS))
    if "mssim" in metrics and min(resolution) < SSIM_MIN_SIDE:
        ck.fail("resolution", f"MSSIM needs images of at least {SSIM_MIN_SIDE}x{SSIM_MIN_SIDE} "
                f"pixels (its window); drop 'mssim' from metrics or raise the resolution")
    figures = ck.names(d["figures"], "figures", FIGURES)
    save = ck.list_(d["save_frames"], "save_frames", nonempty=False)
    save_frames = tuple(sorted({ck.int_(v, f"save_frames[{i}]", lo=0)
                                for i, v in enumerate(save)}))
    timing = TimingSpec(**read_table(ck, d["timing"], "timing", TimingSpec))
    if timing.outputs not in TIMED_OUTPUTS:
        ck.fail("timing.outputs", f"expected one of {', '.join(map(repr, TIMED_OUTPUTS))}, "
                f"got {timing.outputs!r}")
    scenes = _unique(ck, [_scene(ck, item, f"scenes[{i}]", local, study_dir) for i, item in
                          enumerate(ck.list_(d["scenes"], "scenes"))],
                     "label", "scenes", "scene label", "; set `label`")
    if d["paths"] is None:
        paths = (PathSpec("static", "static", frames),)
    else:
        paths = _unique(ck, [_path(ck, item, f"paths[{i}]", local, frames) for i, item in
                             enumerate(ck.list_(d["paths"], "paths"))],
                        "name", "paths", "camera path name")
    pipelines = _unique(ck, [_pipeline(ck, item, f"pipelines[{i}]", local, resolution)
                             for i, item in enumerate(ck.list_(d["pipelines"], "pipelines"))],
                        "label", "pipelines", "pipeline label",
                        "; give each entry a distinct `label`")
    matching.check(ck, pipelines, metrics)
    reference = _reference(ck, d["reference"], resolution)
    return Study(file, d["name"], d["description"], resolution, scenes, paths, pipelines,
                 reference, metrics, figures, save_frames, timing, d["warmup_frames"])
