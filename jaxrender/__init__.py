"""jaxrender: study real-time shading architectures on identical scenes, measured in JAX."""

__version__ = "0.1.0"
