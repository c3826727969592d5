"""Shading pipelines. Each module registers one ``render(scene, camera, cfg) -> Frame``."""

from jaxrender.pipelines.registry import (  # noqa: F401
    REGISTRY,
    RenderConfig,
    get_pipeline,
    list_pipelines,
    make_config,
    register,
)

from jaxrender.pipelines.base import COUNT_KEYS, PipelineConfig  # noqa: E402,F401

# Pipeline modules are imported here as they land, so that registration happens on import.
from jaxrender.pipelines import reference  # noqa: E402,F401
from jaxrender.pipelines import forward  # noqa: E402,F401
from jaxrender.pipelines import deferred  # noqa: E402,F401
from jaxrender.pipelines import visbuffer  # noqa: E402,F401
from jaxrender.pipelines import dacs  # noqa: E402,F401
from jaxrender.pipelines import checkerboard  # noqa: E402,F401
from jaxrender.pipelines import object_space  # noqa: E402,F401
