"""The Scene pytree: one flat triangle array with per-triangle material and object ids, the
materials, the texture atlas, the lights, a default camera and the static effect flags."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxrender.scene.animation import DEFAULT_FPS, Animation, build_animation, reach
from jaxrender.scene.camera import Camera
from jaxrender.scene.effects import BRDF_NAMES, LAMBERT, Effects
from jaxrender.scene.lights import Lights
from jaxrender.scene.materials import Material, Materials, pack_materials
from jaxrender.scene.mesh import MeshPart, complete
from jaxrender.scene.textures import Textures, pack_textures
from jaxrender.types import Array, pytree_dataclass, static_field


@pytree_dataclass
class ShadowMap:
    """An orthographic shadow map of the first directional light.

    depth float32[S, S] window depth in [0, 1] (1 = empty), row 0 at the top (+up side).
    origin float32[3] centre of the light's box; basis float32[3, 3] rows (right, up, to_light);
    half_extent float32[3] half sizes of the box along those rows.
    """

    depth: Array
    origin: Array
    basis: Array
    half_extent: Array


@pytree_dataclass
class Scene:
    """positions float32[V,3] world; normals float32[V,3] (unit or 0); uvs float32[V,2];
    tangents float32[V,4]; velocity float32[V,3] declared world displacement per frame (VRS by speed);
    faces int32[T,3]; tri_material int32[T]; tri_object int32[T] (mesh/instance id);
    bounds float32[2,3] (min, max corner; of every pose of a moving scene,
    ``animation.reach``); materials; textures; lights; camera (the default camera); shadow
    (ShadowMap or None; filled by ``shading.with_shadow_map``);
    animation (``scene.animation.Animation``, or None for a scene that does not move; the
    arrays above are its rest pose, ``animation.pose(scene, t)`` the scene at frame t);
    effects (static); name, description (static)."""

    positions: Array
    normals: Array
    uvs: Array
    tangents: Array
    velocity: Array
    faces: Array
    tri_material: Array
    tri_object: Array
    bounds: Array
    materials: Materials
    textures: Textures
    lights: Lights
    camera: Camera
    shadow: ShadowMap | None = None
    animation: Animation | None = None
    effects: Effects = static_field(default=Effects())
    name: str = static_field(default="scene")
    description: str = static_field(default="")

    @property
    def num_triangles(self) -> int:
        return self.faces.shape[0]

    @property
    def num_vertices(self) -> int:
        return self.positions.shape[0]


def derive_effects(materials: list[Material], animated: bool, shadows: bool) -> Effects:
    """The default effects: exactly what the scene's materials and lights use."""
    return Effects(
        textures=any(m.texture >= 0 for m in materials),
        normal_map=any(m.normal_map >= 0 for m in materials),
        specular=any(m.brdf != "lambert" and max(m.specular) > 0 for m in materials),
        shadows=shadows,
        alpha_test=any(m.alpha_tested for m in materials),
        emissive=any(max(m.emissive) > 0 for m in materials),
        motion=animated,
        procedural=any(m.procedural != "none" for m in materials),
        transparency=any(m.transparent for m in materials),
        brdfs=tuple(sorted({BRDF_NAMES[m.brdf] for m in materials} | {LAMBERT})),
    )


def build_scene(parts: list[MeshPart], materials: list[Material], textures: list[np.ndarray],
                lights: Lights, camera: Camera, *, name: str, description: str = "",
                shadows: bool = False, effects: dict | Effects | None = None,
                texture_resolution: int | None = None, fps: float = DEFAULT_FPS) -> Scene:
    """Flatten mesh parts (already in world space) into one Scene. Each part is one object id;
    a part's ``motion`` (an ``animation.ObjectMotion``) animates it, frames at ``fps``.

    effects: None for the derived default, a dict of overrides on top of it, or an Effects.
    The ``motion`` flag follows the parts' motion (it cannot be set apart from it).
    """
    if not parts:
        raise ValueError(f"scene {name!r}: no meshes")
    materials = list(materials) or [Material()]
    parts = [complete(p) for p in parts]
    offs = np.cumsum([0] + [len(p.positions) for p in parts])
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offs)])
    tri_mat = np.concatenate([np.broadcast_to(np.asarray(p.material), (len(p.faces),))
                              for p in parts]).astype(np.int64)
    if tri_mat.size and (tri_mat.min() < 0 or tri_mat.max() >= len(materials)):
        raise ValueError(f"scene {name!r}: material index {tri_mat.max()} out of range "
                         f"({len(materials)} materials)")
    for m in materials:
        for key in ("texture", "normal_map"):
            if getattr(m, key) >= len(textures):
                raise ValueError(f"scene {name!r}: material {m.name!r} {key} index "
                                 f"{getattr(m, key)} out of range ({len(textures)} textures)")
    check_opacity_textures(materials, textures, name)
    tri_obj = np.concatenate([np.full(len(p.faces), i) for i, p in enumerate(parts)])
    cat = lambda k: np.concatenate([getattr(p, k) for p in parts], 0)  # noqa: E731
    vel = np.concatenate([np.broadcast_to(np.zeros(3) if p.velocity is None else p.velocity,
                                          (len(p.positions), 3)) for p in parts])
    pos = cat("positions")
    if faces.size and (faces.min() < 0 or faces.max() >= len(pos)):
        raise ValueError(f"scene {name!r}: a face refers to a missing vertex")
    if len(faces) >= 2**31 - 1:
        raise ValueError(f"scene {name!r}: too many triangles for int32 ids")
    vertex_object = np.concatenate([np.full(len(p.positions), i) for i, p in enumerate(parts)])
    anim = build_animation([p.motion for p in parts], pos, cat("normals"), cat("tangents"),
                           vertex_object, fps)
    used = materials  # all declared materials count for the default effects
    default = derive_effects(used, anim is not None, shadows)
    if isinstance(effects, Effects):
        eff = effects
    else:
        eff = default.replace(**(effects or {}))
    if eff.motion != (anim is not None):
        raise ValueError(f"scene {name!r}: effects.motion={eff.motion} but the scene "
                         f"{'moves' if anim is not None else 'has no animation'}; the flag "
                         f"follows the meshes' motion")
    if eff.transparency != default.transparency:
        raise ValueError(f"scene {name!r}: effects.transparency={eff.transparency} but "
                         f"{'no' if default.transparency else 'a'} material blends; the flag "
                         f"follows the materials' blend modes")
    f32 = lambda a: jnp.asarray(np.asarray(a, np.float32))  # noqa: E731
    i32 = lambda a: jnp.asarray(np.asarray(a, np.int32))  # noqa: E731
    if anim is None:
        lo = pos.min(0) if len(pos) else np.zeros(3)
        hi = pos.max(0) if len(pos) else np.zeros(3)
    else:  # every pose inside, so that the shadow map's light box holds the moving scene
        lo, hi = reach(anim)
    return Scene(
        positions=f32(pos), normals=f32(cat("normals")), uvs=f32(cat("uvs")),
        tangents=f32(cat("tangents")), velocity=f32(vel), faces=i32(faces),
        tri_material=i32(tri_mat), tri_object=i32(tri_obj), bounds=f32(np.stack([lo, hi])),
        materials=pack_materials(materials),
        textures=pack_textures(textures, resolution=texture_resolution),
        lights=lights, camera=camera, shadow=None, animation=anim, effects=eff, name=name,
        description=description,
    )


def texture_has_alpha(image: np.ndarray) -> bool:
    """Whether an RGBA texture image carries an alpha channel worth reading (not all 1)."""
    img = np.asarray(image)
    return img.ndim == 3 and img.shape[-1] == 4 and bool(np.any(img[..., 3] < 1.0))


def check_opacity_textures(materials: list[Material], textures: list, name: str) -> None:
    """Refuse a material that takes its opacity from a texture without alpha."""
    for m in materials:
        if m.opacity_source == "texture_alpha" and not (
                0 <= m.texture < len(textures) and texture_has_alpha(textures[m.texture])):
            raise ValueError(f"scene {name!r}: material {m.name!r} opacity_source = "
                             f"\"texture_alpha\" but its texture {m.texture} has no alpha "
                             f"channel (every texel opaque)")


def with_effects(scene: Scene, **changes) -> Scene:
    """The scene with some effect flags overridden (unknown flag names raise KeyError)."""
    return dataclasses.replace(scene, effects=scene.effects.replace(**changes))


def default_camera(scene: Scene) -> Camera:
    return scene.camera


def advance(scene: Scene, frames) -> Scene:
    """The scene moved by ``frames`` frames of its per-vertex velocity (motion studies)."""
    return dataclasses.replace(scene, positions=scene.positions + scene.velocity * jnp.asarray(frames, jnp.float32))
