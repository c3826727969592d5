"""TOML tables read into spec dataclasses, every mistake a StudyError naming the file and the
key path (``studies/x.toml: pipelines[2].sweep.threshold: expected a non-empty list``)."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

from jaxrender.errors import StudyError

def type_name(v) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def key_path(path: str, key) -> str:
    return f"{path}.{key}" if path else str(key)


class Checker:
    """Typed accessors that raise StudyError naming the file and the key path."""

    def __init__(self, file: str):
        self.file = file

    def fail(self, path: str, msg: str):
        raise StudyError(self.file, path, msg)

    def table(self, v, path) -> dict:
        if not isinstance(v, dict):
            self.fail(path, f"expected a table, got {type_name(v)}")
        return v

    def keys(self, d: dict, path: str, allowed, required=(), hint: str = ""):
        for k in d:
            if k not in allowed:
                self.fail(key_path(path, k), f"unknown key; allowed keys: {', '.join(sorted(allowed))}")
        for k in required:
            if k not in d:
                self.fail(path or "(top level)", f"missing required key {k!r}{hint}")

    def str_(self, v, path, empty=False) -> str:
        if not isinstance(v, str) or not (v or empty):
            self.fail(path, f"expected a {'' if empty else 'non-empty '}string, "
                      f"got {type_name(v)}")
        return v

    def int_(self, v, path, lo=None) -> int:
        if not isinstance(v, int) or isinstance(v, bool):
            self.fail(path, f"expected an integer, got {type_name(v)}")
        if lo is not None and v < lo:
            self.fail(path, f"expected an integer >= {lo}, got {v}")
        return v

    def num(self, v, path) -> float:
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            self.fail(path, f"expected a finite number, got {v!r}")
        return float(v)

    def bool_(self, v, path) -> bool:
        if not isinstance(v, bool):
            self.fail(path, f"expected true or false, got {type_name(v)}")
        return v

    def list_(self, v, path, nonempty=True) -> list:
        if not isinstance(v, list):
            self.fail(path, f"expected a list, got {type_name(v)}")
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

    def value(self, v, path, kind, **meta):
        """``v`` checked as a ``kind`` (a type or its name); tables and lists stay as read."""
        kind = getattr(kind, "__name__", kind)
        if kind == "bool":
            return self.bool_(v, path)
        if kind == "int":
            return self.int_(v, path, meta.get("lo"))
        if kind == "float":
            return self.num(v, path)
        if kind == "str":
            return self.str_(v, path, meta.get("empty", False))
        if meta.get("table"):
            return dict(self.table(v, path))
        return v


def read_table(ck: Checker, raw, path: str, cls, *, extra=(), defaults=None, hint="") -> dict:
    """The table ``raw`` read as the fields of spec dataclass ``cls`` (plus the TOML-only keys
    ``extra``): unknown keys and missing required ones (no default here or in ``defaults``)
    are errors; each value is checked against its field's type (integers with the field's
    ``lo``, tables as tables); the rest stays as read, for the caller to resolve."""
    fields = [f for f in dataclasses.fields(cls) if f.metadata.get("toml", True)]
    raw = ck.table(raw if raw is not None else {}, path or "(top level)")
    defaults = defaults or {}
    missing = [f.name for f in fields if f.metadata.get("required") or (
        f.name not in defaults and f.default is dataclasses.MISSING)]
    ck.keys(raw, path, {f.name for f in fields} | set(extra), required=missing, hint=hint)
    out = {}
    for f in fields:
        if f.name in raw:
            out[f.name] = ck.value(raw[f.name], key_path(path, f.name), f.type, **f.metadata)
        else:
            empty = {} if f.metadata.get("table") and f.default == () else f.default
            out[f.name] = defaults.get(f.name, empty)
    return out | {k: raw[k] for k in extra if k in raw}


def read_toml(path: Path, shown: str) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise StudyError(shown, "", "no such file") from None
    except tomllib.TOMLDecodeError as e:
        raise StudyError(shown, "", f"invalid TOML: {e}") from None


def shown_path(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)

