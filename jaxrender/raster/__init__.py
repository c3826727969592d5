"""Geometry -> visibility: transform, clip, fixed-point snap, exact coverage, resolve."""

from jaxrender.raster import samples  # noqa: F401
from jaxrender.raster.fragments import Fragments, fragments  # noqa: F401
from jaxrender.raster.rasterize import rasterize, rasterize_clip  # noqa: F401
