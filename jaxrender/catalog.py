"""Where presets, scene files and studies are found: built into the package, and in a local
``configs/`` folder that adds to them and overrides a built-in of the same name.

The built-ins ship as package data (``jaxrender/configs/{paths,pipelines,scenes}/*.toml`` and
``jaxrender/studies/*.toml``), so an installed jaxrender finds them from any directory. A
user's own ``configs/`` (beside the study file, or named with ``--configs DIR``) holds the
same three folders.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

PACKAGE_DIR = Path(__file__).resolve().parent
BUILTIN = "built-in"

# kind (a folder under a configs root; "studies": the package's studies folder) -> what one is called
KINDS = {
    "paths": "camera path preset",
    "pipelines": "pipeline preset",
    "scenes": "scene file",
    "studies": "study",
}


@dataclass(frozen=True)
class Entry:
    """One preset, scene file or study: its name, file and where it comes from (``built-in``,
    or the local configs folder that holds it)."""

    kind: str
    name: str
    path: Path
    source: str
    hides_builtin: bool = False  # a local file named as a built-in one, which it overrides

    @property
    def builtin(self) -> bool:
        return self.source == BUILTIN

    def describe(self) -> str:
        note = ", overrides the built-in" if self.hides_builtin else ""
        return f"{self.source} ({self.path}{note})"


def builtin_dir(kind: str) -> Path:
    check_kind(kind)
    if kind == "studies":
        return PACKAGE_DIR / "studies"
    return PACKAGE_DIR / "configs" / kind


def check_kind(kind: str) -> None:
    if kind not in KINDS:
        raise ValueError(f"unknown kind {kind!r}; one of {', '.join(KINDS)}")


def _same_dir(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def nearest_configs(start: Path) -> Path | None:
    """The nearest ``configs/`` folder at or above ``start``."""
    start = Path(start).resolve()
    for d in [start, *start.parents]:
        if (d / "configs").is_dir():
            return d / "configs"
    return None


def local_configs(start: Path | None = None, explicit: Path | None = None) -> list[Path]:
    """The local configs folders to search, most specific first: ``explicit`` (``--configs``)
    when given, else the nearest ``configs/`` at or above ``start`` (a study file's folder).
    A folder that is the package's own (a source checkout links ``configs`` to it) is not
    local."""
    if explicit is not None:
        explicit = Path(explicit)
        if not explicit.is_dir():
            raise FileNotFoundError(f"configs folder {explicit} not found")
        found = [explicit]
    else:
        nearest = nearest_configs(start) if start is not None else None
        found = [nearest] if nearest else []
    return [d for d in found if not _same_dir(d, PACKAGE_DIR / "configs")]


def _folders(kind: str, local: Iterable[Path]) -> list[tuple[Path, str]]:
    """(folder, source) to search, the first hit wins: local folders, then the built-in."""
    check_kind(kind)
    out = [] if kind == "studies" else [(Path(d) / kind, str(Path(d))) for d in local]
    return out + [(builtin_dir(kind), BUILTIN)]


def entries(kind: str, local: Iterable[Path] = ()) -> dict[str, Entry]:
    """Every entry of ``kind`` by name; a local file hides the built-in of the same name."""
    found: dict[str, Entry] = {}
    for folder, source in reversed(_folders(kind, list(local))):
        for path in sorted(folder.glob("*.toml")):
            hides = path.stem in found and found[path.stem].builtin
            found[path.stem] = Entry(kind, path.stem, path.resolve(), source, hides)
    return dict(sorted(found.items()))


def find(kind: str, name: str, local: Iterable[Path] = ()) -> Entry | None:
    return entries(kind, local).get(name)


def available(kind: str, local: Iterable[Path] = ()) -> str:
    """The names on offer, for an error message: ``a, b (local), c``; ``(none)`` if empty."""
    names = [e.name + ("" if e.builtin else " (local)") for e in entries(kind, local).values()]
    return ", ".join(names) or "(none)"
