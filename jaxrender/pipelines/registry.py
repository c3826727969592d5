"""The pipeline registry: one ``render(scene, camera, cfg) -> Frame`` per ``type`` string.

Every pipeline module registers itself with ``@register("name", ConfigClass)``. A config class
is a frozen (hashable, hence static under jit) dataclass deriving from ``RenderConfig``; the
study runner builds it from TOML with ``make_config``, which rejects unknown keys by name.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, NamedTuple


@dataclass(frozen=True)
class RenderConfig:
    """Static settings shared by every pipeline: the output resolution in pixels."""

    width: int = 320
    height: int = 180


class Pipeline(NamedTuple):
    name: str
    config_cls: type
    render: Callable  # render(scene, camera, cfg) -> Frame
    description: str


REGISTRY: dict[str, Pipeline] = {}


def register(name: str, config_cls: type, description: str = ""):
    if not (dataclasses.is_dataclass(config_cls) and issubclass(config_cls, RenderConfig)):
        raise TypeError(f"pipeline {name!r}: config must be a RenderConfig dataclass")

    def wrap(render: Callable) -> Callable:
        if name in REGISTRY:
            raise ValueError(f"pipeline {name!r} is registered twice")
        doc = description or (render.__doc__ or "").strip().splitlines()[0]
        REGISTRY[name] = Pipeline(name, config_cls, render, doc)
        return render

    return wrap


def get_pipeline(name: str) -> Pipeline:
    _load_builtin_pipelines()
    try:
        return REGISTRY[name]
    except KeyError:
        known = ", ".join(sorted(REGISTRY)) or "(none)"
        raise KeyError(f"unknown pipeline {name!r}; registered pipelines: {known}") from None


def make_config(name: str, **params):
    """The pipeline's config from keyword parameters; unknown keys raise, naming the key."""
    cls = get_pipeline(name).config_cls
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(params) - fields)
    if unknown:
        raise KeyError(
            f"pipeline {name!r} has no parameter {unknown[0]!r}; "
            f"its parameters are: {', '.join(sorted(fields))}"
        )
    return cls(**params)


def list_pipelines() -> list[Pipeline]:
    _load_builtin_pipelines()
    return [REGISTRY[k] for k in sorted(REGISTRY)]


def _load_builtin_pipelines() -> None:
    # Importing the package imports every pipeline module, each of which registers itself.
    import jaxrender.pipelines  # noqa: F401
