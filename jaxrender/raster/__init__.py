"""Geometry -> visibility: transform, clip, fixed-point snap, exact coverage, resolve."""

from jaxrender.raster import samples  # noqa: F401
from jaxrender.raster.fragments import Fragments, fragments  # noqa: F401
from jaxrender.raster.rasterize import (  # noqa: F401
    rasterize, rasterize_clip, rasterize_depth, rasterize_depth_clip)
