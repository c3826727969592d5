"""jaxrender: study real-time shading architectures on identical scenes, measured in JAX."""

from jaxrender.version import VERSION as __version__  # noqa: F401
