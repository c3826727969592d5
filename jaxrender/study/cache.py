"""The reference cache: ground-truth frames on disk, outside git.

Location: ``$JAXRENDER_CACHE`` if set, else ``$XDG_CACHE_HOME/jaxrender`` (``~/.cache/
jaxrender``), subfolder ``reference/``. One ``.npz`` per frame, keyed by a hash of the scene
(name, size parameters and the scene file's bytes), the camera's arrays, the reference
pipeline and its settings, the resolution and the code version (package version plus a hash of
the source files of raster/, shading/, scene/ and pipelines/). Files are written to a temporary
name, fsync'd and renamed, so a reader never sees half a file. ``jaxrender reference rebuild``
re-renders the entries of a study (``references.rebuild``); ``jaxrender reference clear`` empties the cache.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
from pathlib import Path

import jax
import numpy as np

from jaxrender.version import VERSION

# What a reference frame depends on: the rendering packages and the helpers below them.
_CODE_DIRS = ("raster", "shading", "scene", "pipelines")
_CODE_FILES = ("types.py", "compaction.py", "sorting.py", "catalog.py")


def cache_root() -> Path:
    """jaxrender's cache folder: ``$JAXRENDER_CACHE``, else ``$XDG_CACHE_HOME/jaxrender``."""
    env = os.environ.get("JAXRENDER_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "jaxrender"


def cache_dir() -> Path:
    """Where reference frames are kept."""
    return cache_root() / "reference"


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """jaxrender's version and a hash of the sources a reference image depends on."""
    root = Path(__file__).resolve().parents[1]  # the jaxrender package
    h = hashlib.sha256()
    files = [f for d in _CODE_DIRS for f in sorted((root / d).rglob("*.py"))]
    for f in files + [root / name for name in _CODE_FILES]:
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes() + b"\0")
    return f"{VERSION}+{h.hexdigest()[:12]}"


def camera_digest(camera) -> str:
    h = hashlib.sha256()
    for leaf in jax.tree_util.tree_leaves(camera):
        a = np.ascontiguousarray(np.asarray(leaf))
        h.update(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())
    return h.hexdigest()


def reference_key(scene_spec, camera, ref_spec, resolution, frame: int | None = None) -> str:
    """The cache key of a reference frame; ``frame``: its index on the animation clock, for a
    scene that moves (a still scene's frame is its camera alone)."""
    parts = {
        "scene": [scene_spec.source, list(map(list, scene_spec.params)), scene_spec.file_hash],
        "camera": camera_digest(camera),
        "pipeline": ref_spec.pipeline,
        "params": [list(p) for p in ref_spec.params],
        "resolution": list(resolution),
        "code": code_version(),
    }
    if frame is not None:
        parts["frame"] = int(frame)
    blob = json.dumps(parts, sort_keys=True, default=repr).encode()
    return hashlib.sha256(blob).hexdigest()[:32]


def _path(key: str, root: Path | None = None) -> Path:
    return (root or cache_dir()) / f"{key}.npz"


def has(key: str, root: Path | None = None) -> bool:
    return _path(key, root).exists()


def load(key: str, root: Path | None = None) -> dict | None:
    """The cached arrays, or None when missing or unreadable (then it is rebuilt)."""
    p = _path(key, root)
    if not p.exists():
        return None
    try:
        with np.load(p) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError):
        return None


def save(key: str, arrays: dict, root: Path | None = None) -> Path:
    p = _path(key, root)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.stem}.{os.getpid()}.tmp.npz")
    with open(tmp, "wb") as f:
        np.savez_compressed(f, **arrays)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, p)
    return p


def remove(key: str, root: Path | None = None) -> bool:
    p = _path(key, root)
    if p.exists():
        p.unlink()
        return True
    return False


def clear(root: Path | None = None) -> int:
    """Delete every cached reference; returns how many files were removed."""
    d = root or cache_dir()
    if not d.exists():
        return 0
    n = len(list(d.glob("*.npz")))
    shutil.rmtree(d)
    return n


def info(root: Path | None = None) -> dict:
    d = root or cache_dir()
    files = list(d.glob("*.npz")) if d.exists() else []
    return {"path": str(d), "entries": len(files),
            "bytes": sum(f.stat().st_size for f in files), "code_version": code_version()}
