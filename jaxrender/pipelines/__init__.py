"""Shading pipelines. Each module registers one pipeline (a ``step``, or a stateless
``frame``) with the registry; ``program`` compiles and runs them all alike."""

from jaxrender.pipelines.registry import (  # noqa: F401
    REGISTRY,
    Pipeline,
    RenderConfig,
    get_pipeline,
    list_pipelines,
    make_config,
    register,
    register_frame,
)

from jaxrender.pipelines.base import COUNT_KEYS, PipelineConfig  # noqa: E402,F401
from jaxrender.pipelines.program import PipelineOverflow  # noqa: E402,F401

# Importing a pipeline module registers it.
from jaxrender.pipelines import reference  # noqa: E402,F401
from jaxrender.pipelines import forward  # noqa: E402,F401
from jaxrender.pipelines import deferred  # noqa: E402,F401
from jaxrender.pipelines import visbuffer  # noqa: E402,F401
from jaxrender.pipelines import dacs  # noqa: E402,F401
from jaxrender.pipelines import checkerboard  # noqa: E402,F401
from jaxrender.pipelines import object_space  # noqa: E402,F401
from jaxrender.pipelines import tads  # noqa: E402,F401
