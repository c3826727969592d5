"""Surface points -> colour: BRDFs, textures and MIP filtering, lights, shadows, ``shade``."""

from jaxrender.shading.lit_scene import load_lit_scene
from jaxrender.shading.shade import alpha, alpha_test, opacity, shade, texture_sample
from jaxrender.shading.shadow import render_shadow_map, shadow_factor, with_shadow_map
from jaxrender.shading.surface import surface_points, view_depth

__all__ = ["alpha", "alpha_test", "load_lit_scene", "opacity", "render_shadow_map", "shade",
           "shadow_factor", "surface_points", "texture_sample", "view_depth", "with_shadow_map"]
