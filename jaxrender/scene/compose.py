"""Objects added to an existing scene: a scene file's ``base = "<built-in scene>"`` puts its
meshes (transparent panes, particles, anything) into that scene, under its lights and camera.

The new parts are built into a scene of their own (``build_scene``) and the two are joined
array by array: vertices and faces appended (indices shifted), materials and textures appended
(the new materials' texture indices shifted past the base's), object ids continued, and the
effects the union of both scenes' (a flag on in either is on; the BRDF kinds of both). A
moving base scene is refused: its animation is per vertex of its own meshes.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.scene.effects import Effects
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import MeshPart
from jaxrender.scene.scene import Scene, build_scene
from jaxrender.scene.textures import Textures


def add_objects(base: Scene, parts: list[MeshPart], materials: list[Material],
                textures: list[np.ndarray]) -> Scene:
    """``base`` with the mesh ``parts`` (world space; their material indices into
    ``materials``) added. Raises ValueError for a moving base or moving parts."""
    if base.animation is not None or any(p.motion is not None for p in parts):
        raise ValueError(f"scene {base.name!r}: objects can be added to a still scene only "
                         f"(its animation is per vertex of its own meshes)")
    res = base.textures.resolution if base.effects.textures else None
    extra = build_scene(parts, materials, textures, base.lights, base.camera, name=base.name,
                        texture_resolution=res)
    n_tex = base.textures.atlas.shape[0] if base.effects.textures and textures else 0
    shift = lambda t: jnp.where(t >= 0, t + n_tex, t)  # noqa: E731
    new_mats = dataclasses.replace(extra.materials, texture=shift(extra.materials.texture),
                                   normal_map=shift(extra.materials.normal_map))
    cat = lambda a, b: jnp.concatenate([a, b])  # noqa: E731
    if not textures:
        atlas = base.textures
    elif not base.effects.textures:
        atlas = extra.textures
    else:
        atlas = Textures(cat(base.textures.atlas, extra.textures.atlas))
    n_obj = int(jnp.max(base.tri_object)) + 1
    return dataclasses.replace(
        base,
        positions=cat(base.positions, extra.positions), normals=cat(base.normals, extra.normals),
        uvs=cat(base.uvs, extra.uvs), tangents=cat(base.tangents, extra.tangents),
        velocity=cat(base.velocity, extra.velocity),
        faces=cat(base.faces, extra.faces + base.num_vertices),
        tri_material=cat(base.tri_material, extra.tri_material + base.materials.count),
        tri_object=cat(base.tri_object, extra.tri_object + n_obj),
        bounds=jnp.stack([jnp.minimum(base.bounds[0], extra.bounds[0]),
                          jnp.maximum(base.bounds[1], extra.bounds[1])]),
        materials=jax.tree_util.tree_map(cat, base.materials, new_mats), textures=atlas,
        effects=union(base.effects, extra.effects))


def union(a: Effects, b: Effects) -> Effects:
    """Every boolean flag on in either, the BRDF kinds of both; the rest ``a``'s."""
    changes = {f.name: getattr(a, f.name) or getattr(b, f.name)
               for f in dataclasses.fields(Effects) if f.type in (bool, "bool")}
    return a.replace(brdfs=tuple(sorted(set(a.brdfs) | set(b.brdfs))), **changes)
