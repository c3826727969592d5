"""Materials: a Python-side ``Material`` description and the packed ``Materials`` pytree.

``Materials`` holds one array per property with a leading material axis ``[M, ...]``; the shader
gathers a row per surface point by ``SurfacePoints.material``.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxrender.scene.effects import BRDF_NAMES, PROCEDURAL_NAMES
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

    def __post_init__(self):
        if self.brdf not in BRDF_NAMES:
            raise ValueError(f"material {self.name!r}: brdf {self.brdf!r} not in {sorted(BRDF_NAMES)}")
        if self.procedural not in PROCEDURAL_NAMES:
            raise ValueError(
                f"material {self.name!r}: procedural {self.procedural!r} "
                f"not in {sorted(PROCEDURAL_NAMES)}"
            )


@pytree_dataclass
class Materials:
    """Per-material arrays, M rows.

    albedo float32[M,3]; specular float32[M,3] (Blinn-Phong ks / GGX F0); shininess float32[M];
    roughness float32[M]; brdf int32[M] (effects.LAMBERT/BLINN_PHONG/GGX); texture int32[M]
    (-1 none); normal_map int32[M] (-1 none); alpha float32[M]; alpha_tested bool[M];
    alpha_cutoff float32[M]; emissive float32[M,3]; procedural int32[M];
    stripe_resolution float32[M].
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
    )
