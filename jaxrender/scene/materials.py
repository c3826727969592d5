"""Materials: a Python-side ``Material`` description and the packed ``Materials`` pytree.

``Materials`` holds one array per property with a leading material axis ``[M, ...]``; the shader
gathers a row per surface point by ``SurfacePoints.material``.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

import math

from jaxrender.scene.effects import BLEND_NAMES, BRDF_NAMES, OPACITY_SOURCES, PROCEDURAL_NAMES
from jaxrender.types import Array, pytree_dataclass


@dataclass(frozen=True)
class Material:
    """One material as written by a scene author (colours linear RGB).

    texture / normal_map: index into the scene's texture list, -1 for none.
    shininess: Blinn-Phong exponent (any value >= 0; 1e6 stays finite).
    roughness: GGX roughness in (0, 1] (alpha = roughness**2).
    alpha: base opacity multiplied with the texture's alpha; alpha_cutoff: the alpha test keeps
    a point when alpha >= alpha_cutoff (only for alpha_tested materials).
    procedural: "none" or "stripes" (IntTexCoord.x % 2 == 0 ? 1 : 0 at stripe_resolution).
    blend: "opaque", "over" or "additive" (``effects.BLEND_NAMES``); a blended material is drawn
    by the transparent pass with opacity ``opacity`` in [0, 1], times the texture's alpha when
    opacity_source = "texture_alpha" (needs a texture with an alpha channel). An opaque
    material refuses opacity settings (they would be ignored).
    """

    name: str = "default"
    albedo: tuple = (0.8, 0.8, 0.8)
    specular: tuple = (0.0, 0.0, 0.0)
    shininess: float = 32.0
    roughness: float = 0.5
    brdf: str = "lambert"
    texture: int = -1
    normal_map: int = -1
    alpha: float = 1.0
    alpha_tested: bool = False
    alpha_cutoff: float = 0.5
    emissive: tuple = (0.0, 0.0, 0.0)
    procedural: str = "none"
    stripe_resolution: float = 256.0
    blend: str = "opaque"
    opacity: float = 1.0
    opacity_source: str = "constant"

    @property
    def transparent(self) -> bool:
        return self.blend != "opaque"

    def __post_init__(self):
        self._check_blend()
        if self.brdf not in BRDF_NAMES:
            raise ValueError(f"material {self.name!r}: brdf {self.brdf!r} not in {sorted(BRDF_NAMES)}")
        if self.procedural not in PROCEDURAL_NAMES:
            raise ValueError(
                f"material {self.name!r}: procedural {self.procedural!r} "
                f"not in {sorted(PROCEDURAL_NAMES)}"
            )

    def _check_blend(self):
        """Each problem names the field, so a scene file can name its key."""
        if self.blend not in BLEND_NAMES:
            raise ValueError(f"material {self.name!r}: blend {self.blend!r} not in "
                             f"{sorted(BLEND_NAMES)}")
        if self.opacity_source not in OPACITY_SOURCES:
            raise ValueError(f"material {self.name!r}: opacity_source {self.opacity_source!r} "
                             f"not in {list(OPACITY_SOURCES)}")
        op = float(self.opacity)
        if not (math.isfinite(op) and 0.0 <= op <= 1.0):
            raise ValueError(f"material {self.name!r}: opacity must be in [0, 1], got {op}")
        if not self.transparent and (op != 1.0 or self.opacity_source != "constant"):
            raise ValueError(f"material {self.name!r}: opacity and opacity_source have no "
                             f"effect with blend = \"opaque\"; set blend to \"over\" or "
                             f"\"additive\"")
        if self.opacity_source == "texture_alpha" and self.texture < 0:
            raise ValueError(f"material {self.name!r}: opacity_source = \"texture_alpha\" "
                             f"needs a texture")
        if self.transparent and self.alpha_tested:
            raise ValueError(f"material {self.name!r}: a blended material cannot also be "
                             f"alpha_tested (use opacity_source = \"texture_alpha\")")


@pytree_dataclass
class Materials:
    """Per-material arrays, M rows.

    albedo float32[M,3]; specular float32[M,3] (Blinn-Phong ks / GGX F0); shininess float32[M];
    roughness float32[M]; brdf int32[M] (effects.LAMBERT/BLINN_PHONG/GGX); texture int32[M]
    (-1 none); normal_map int32[M] (-1 none); alpha float32[M]; alpha_tested bool[M];
    alpha_cutoff float32[M]; emissive float32[M,3]; procedural int32[M];
    stripe_resolution float32[M]; blend int32[M] (effects.BLEND_*); opacity float32[M];
    opacity_texture bool[M] (opacity times the texture's alpha).
    """

    albedo: Array
    specular: Array
    shininess: Array
    roughness: Array
    brdf: Array
    texture: Array
    normal_map: Array
    alpha: Array
    alpha_tested: Array
    alpha_cutoff: Array
    emissive: Array
    procedural: Array
    stripe_resolution: Array
    blend: Array
    opacity: Array
    opacity_texture: Array

    @property
    def count(self) -> int:
        return self.albedo.shape[0]


def pack_materials(materials: list[Material]) -> Materials:
    if not materials:
        materials = [Material()]
    f32 = lambda key: jnp.asarray(np.array([getattr(m, key) for m in materials], np.float32))  # noqa: E731
    i32 = lambda vals: jnp.asarray(np.array(vals, np.int32))  # noqa: E731
    return Materials(
        albedo=f32("albedo"),
        specular=f32("specular"),
        shininess=f32("shininess"),
        roughness=jnp.clip(f32("roughness"), 1e-3, 1.0),
        brdf=i32([BRDF_NAMES[m.brdf] for m in materials]),
        texture=i32([m.texture for m in materials]),
        normal_map=i32([m.normal_map for m in materials]),
        alpha=f32("alpha"),
        alpha_tested=jnp.asarray(np.array([m.alpha_tested for m in materials], bool)),
        alpha_cutoff=f32("alpha_cutoff"),
        emissive=f32("emissive"),
        procedural=i32([PROCEDURAL_NAMES[m.procedural] for m in materials]),
        stripe_resolution=f32("stripe_resolution"),
        blend=i32([BLEND_NAMES[m.blend] for m in materials]),
        opacity=f32("opacity"),
        opacity_texture=jnp.asarray(np.array(
            [m.opacity_source == "texture_alpha" for m in materials], bool)),
    )
