"""Effect flags: what a scene asks the shader to compute, so that a scene that does not ask for
an effect pays nothing for it.

``Effects`` is a frozen, hashable dataclass stored as a *static* field of the scene, so every
flag is a Python branch at trace time: an effect that is off compiles to nothing.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

# BRDF kinds (``Materials.brdf``).
LAMBERT, BLINN_PHONG, GGX = 0, 1, 2
BRDF_NAMES = {"lambert": LAMBERT, "blinn_phong": BLINN_PHONG, "ggx": GGX}

# Procedural shader kinds (``Materials.procedural``).
PROC_NONE, PROC_STRIPES = 0, 1
PROCEDURAL_NAMES = {"none": PROC_NONE, "stripes": PROC_STRIPES}

# Blend modes (``Materials.blend``): opaque surfaces write depth; "over" blends
# a * c + (1 - a) * dst (Porter-Duff over), "additive" dst + a * c (glow, particles).
BLEND_OPAQUE, BLEND_OVER, BLEND_ADDITIVE = 0, 1, 2
BLEND_NAMES = {"opaque": BLEND_OPAQUE, "over": BLEND_OVER, "additive": BLEND_ADDITIVE}

# Where a transparent material's opacity comes from (``Materials.opacity_texture``).
OPACITY_SOURCES = ("constant", "texture_alpha")


@dataclass(frozen=True)
class Effects:
    """Static switches of ``shade``.

    textures:    sample base-colour textures (MIP chain, trilinear or anisotropic).
    normal_map:  perturb the shading normal with tangent-space normal maps.
    specular:    evaluate the specular lobes (Blinn-Phong, GGX); off = diffuse only.
    shadows:     look up the directional shadow map (needs ``scene.shadow``).
    alpha_test:  materials may be alpha-tested; pipelines call ``shading.alpha_test``.
    emissive:    add the emissive term.
    motion:      the scene is animated (``scene.animation``): pipelines pose it at each frame
                 (``animation.pose``); off, no pose is computed. Follows the meshes' motion.
    procedural:  evaluate procedural shaders (the 1-texel stripe shader).
    transparency: materials may blend (``Material.blend`` "over" or "additive"): pipelines run
                 the transparent pass (``pipelines.transparency``); off, none of it is compiled
                 and transparent triangles cannot exist (the flag follows the materials).
    brdfs:       sorted tuple of the BRDF kinds present; only these lobes are compiled.
    shader_cost: number of extra light layers evaluated (0 = the plain shader). Each layer
                 re-evaluates every light with the shading normal nudged by < 1e-3 rad and the
                 layers are averaged, so the image barely changes while the work grows.
    aniso_taps:  1 = isotropic trilinear; n > 1 = n trilinear taps along the major axis of the
                 pixel footprint, LOD from the minor axis (clamped to major / n).
    toksvig:     Toksvig specular anti-aliasing from the shortened filtered normal-map normal.
    shadow_map_size: resolution of the square shadow map (static: it is an array shape).
    shadow_bias: depth bias of the shadow test, in window-depth units.
    """

    textures: bool = False
    normal_map: bool = False
    specular: bool = False
    shadows: bool = False
    alpha_test: bool = False
    emissive: bool = False
    motion: bool = False
    procedural: bool = False
    transparency: bool = False
    brdfs: tuple = (LAMBERT,)
    shader_cost: int = 0
    aniso_taps: int = 1
    toksvig: bool = False
    shadow_map_size: int = 512
    shadow_bias: float = 2e-3

    def __post_init__(self):
        if int(self.shader_cost) < 0:
            raise ValueError(f"Effects.shader_cost must be >= 0, got {self.shader_cost}")
        if int(self.aniso_taps) < 1:
            raise ValueError(f"Effects.aniso_taps must be >= 1, got {self.aniso_taps}")
        if int(self.shadow_map_size) < 1:
            raise ValueError(f"Effects.shadow_map_size must be >= 1, got {self.shadow_map_size}")
        object.__setattr__(self, "brdfs", tuple(sorted({int(b) for b in self.brdfs})))

    def replace(self, **changes) -> "Effects":
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise KeyError(f"Effects has no flag {unknown[0]!r}; flags: {', '.join(sorted(names))}")
        return dataclasses.replace(self, **changes)


EFFECT_FIELDS = {f.name: f.type for f in dataclasses.fields(Effects)}
