"""Scene TOML files (configs/scenes/*.toml), validated once; every error names file and key.

```toml
name = "demo"                      # optional, defaults to the file stem
description = "one line"
texture_resolution = 256           # optional power of two
fps = 60                           # optional: the frame rate of the animation clock
shadows = true                     # optional: shadow map of the first directional light

[camera]                           # required
eye = [0, 1.6, 4]
target = [0, 1, 0]
up = [0, 1, 0]                     # optional
fov_y_deg = 60                     # optional; near, far optional

[[materials]]                      # any number; meshes refer to them by name
name = "floor"
albedo = [0.8, 0.8, 0.8]           # also: specular, shininess, roughness, brdf, texture (image
texture = "floor.png"              # file), normal_map (image file), alpha, alpha_tested,
                                   # alpha_cutoff, emissive, procedural, stripe_resolution
blend = "over"                     # optional: "opaque" (default), "over" or "additive": a
opacity = 0.5                      # transparent surface of opacity in [0, 1], times the
opacity_source = "constant"        # texture's alpha with "texture_alpha" (needs an alpha)
[[meshes]]                         # file = "x.obj|.ply|.glb|.gltf" or primitive = "plane|box|sphere"
primitive = "plane"
size = [10, 10]                    # plane [w, d], box [w, h, d], sphere radius
subdivisions = 4                   # plane grid / sphere latitude bands
uv_scale = [4, 4]                  # plane only
material = "floor"                 # optional override (a file's own materials otherwise)
translate = [0, 0, 0]              # also rotate_deg = [x, y, z], scale = s or [sx, sy, sz],
                                   # velocity = [vx, vy, vz] (world units per frame)
[meshes.motion]                    # optional animation of this mesh (times in seconds)
spin_axis = [0, 1, 0]              # spin_deg_per_s, pivot (default: the mesh's centre),
spin_deg_per_s = 90                # velocity (units/s), orbit_center, orbit_axis,
                                   # orbit_deg_per_s, sway_amplitude, sway_direction,
                                   # sway_frequency_hz, sway_wavelength, sway_height,
                                   # sway_exponent, sway_base (see scene.animation)
[[lights]]
type = "directional"               # direction (towards the light), irradiance
direction = [0.3, 1, 0.2]
irradiance = 2.0                   # scalar or RGB
# type = "point": position, intensity;  type = "ambient": radiance

[effects]                          # optional overrides of the derived Effects flags
shader_cost = 4
```
A file with ``base = "<built-in scene>"`` (say "room") adds its materials and meshes to that
scene instead, under its lights and camera (a ``[camera]`` table overrides it; ``lights``,
``shadows``, ``fps`` and ``texture_resolution`` are the base's): glass panes or particles in
any still built-in scene (``scene.compose``).
Relative paths are relative to the TOML file.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np

from jaxrender.scene.animation import DEFAULT_FPS, ObjectMotion
from jaxrender.scene.camera import look_at
from jaxrender.scene.config_schema import (CAMERA, EFFECTS, LIGHT, LIGHT_KEYS, MATERIAL, MESH,
                                           MOTION, TOP, SceneConfigError, array_of_tables,
                                           check_table, existing_file, rgb)
from jaxrender.scene.effects import BRDF_NAMES
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import box, grid_plane, trs_matrix, uv_sphere
from jaxrender.scene.mesh_io import load_mesh_file
from jaxrender.scene.scene import Scene, build_scene, texture_has_alpha
from jaxrender.scene.textures import as_rgba


def load_scene_toml(path: str | Path, effects: dict | None = None) -> Scene:
    """The scene of a TOML file (see the module docstring); ``effects`` overrides the file's
    flags. Raises SceneConfigError naming the file and the key."""
    path = Path(path)
    data = _read(path)
    if "base" in data:
        return _onto_base(path, data, effects)
    check_table(path, "", data, TOP, required=("camera", "meshes"))
    camera = _camera(path, data)
    materials, textures, by_name = _materials(path, data)
    parts = _meshes(path, data, materials, textures, by_name)
    directional, point, ambient = _lights(path, data)
    if "fps" in data and not any("motion" in m for m in data["meshes"]):
        raise SceneConfigError(path, "fps", "no mesh has a motion table; fps is the rate of "
                               "the animation clock")
    fps = _fps(path, data)
    eff = _effects(path, data)
    eff.update(effects or {})
    try:
        return build_scene(parts, materials, textures, make_lights(directional, point, ambient),
                           camera, name=data.get("name", path.stem),
                           description=data.get("description", ""),
                           shadows=data.get("shadows", False), effects=eff,
                           texture_resolution=data.get("texture_resolution"),
                           fps=fps)
    except (ValueError, KeyError) as e:
        raise SceneConfigError(path, "<scene>", str(e)) from None


def _onto_base(path: Path, data: dict, effects: dict | None) -> Scene:
    """``base = "<built-in scene>"``: the file's meshes added to that scene (its lights; its
    camera unless the file gives one). See ``scene.compose``."""
    from jaxrender.scene.builtin import BUILTINS, builtin_scene
    from jaxrender.scene.compose import add_objects

    check_table(path, "", data, TOP, required=("meshes",))
    if data["base"] not in BUILTINS:
        raise SceneConfigError(path, "base", f"{data['base']!r} is not a built-in scene "
                               f"({', '.join(BUILTINS)})")
    for key in ("lights", "shadows", "fps", "texture_resolution"):
        if key in data:
            raise SceneConfigError(path, key, "is the base scene's (base = "
                                   f"{data['base']!r}); remove it")
    materials, textures, by_name = _materials(path, data)
    parts = _meshes(path, data, materials, textures, by_name)
    try:
        scene = add_objects(builtin_scene(data["base"]), parts, materials, textures)
        eff = dict(_effects(path, data), **(effects or {}))
        if eff:
            scene = dataclasses.replace(scene, effects=scene.effects.replace(**eff))
    except (ValueError, KeyError) as e:
        raise SceneConfigError(path, "<scene>", str(e)) from None
    camera = _camera(path, data) if "camera" in data else scene.camera
    return dataclasses.replace(scene, camera=camera, name=data.get("name", path.stem),
                               description=data.get("description", scene.description))


def _read(path: Path) -> dict:
    try:
        return tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneConfigError(path, "<file>", "scene file not found") from None
    except tomllib.TOMLDecodeError as e:
        raise SceneConfigError(path, "<syntax>", f"not valid TOML: {e}") from None


def _camera(path: Path, data: dict):
    check_table(path, "camera", data["camera"], CAMERA, required=("eye", "target"))
    cam_kw = {k: data["camera"][k] for k in ("up", "fov_y_deg", "near", "far") if k in data["camera"]}
    try:
        return look_at(data["camera"]["eye"], data["camera"]["target"], **cam_kw)
    except ValueError as e:
        raise SceneConfigError(path, "camera", str(e)) from None


def _materials(path: Path, data: dict) -> tuple[list, list, dict]:
    """(materials, texture images, material index by name); each image file is read once per
    colour space."""
    materials, textures, by_name = [], [], {}
    image_index: dict[tuple, int] = {}

    def image(key, name, srgb):
        f = existing_file(path, key, name)
        if (f, srgb) not in image_index:
            import imageio.v3 as iio

            try:
                img = iio.imread(f)
            except Exception as e:  # noqa: BLE001 - any decoder failure names the key
                raise SceneConfigError(path, key, f"cannot read image {name!r}: {e}") from None
            image_index[(f, srgb)] = len(textures)
            textures.append(as_rgba(img, srgb=srgb))
        return image_index[(f, srgb)]

    for i, m in enumerate(array_of_tables(path, data, "materials")):
        pre = f"materials[{i}]"
        check_table(path, pre, m, MATERIAL, required=("name",))
        if m["name"] in by_name:
            raise SceneConfigError(path, f"{pre}.name", f"duplicate material name {m['name']!r}")
        kw = dict(m)
        for k in ("albedo", "specular", "emissive"):
            if k in kw:
                kw[k] = rgb(kw[k])
        if "texture" in kw:
            kw["texture"] = image(f"{pre}.texture", kw["texture"], srgb=True)
        if "normal_map" in kw:
            kw["normal_map"] = image(f"{pre}.normal_map", kw["normal_map"], srgb=False)
        _check_opacity(path, pre, kw, textures)
        by_name[m["name"]] = len(materials)
        try:
            materials.append(Material(**kw))
        except ValueError as e:
            raise SceneConfigError(path, pre, str(e)) from None
    return materials, textures, by_name


def _check_opacity(path: Path, pre: str, kw: dict, textures: list) -> None:
    """The transparency keys of one material, each problem named by its key."""
    if "opacity" in kw and not 0.0 <= float(kw["opacity"]) <= 1.0:
        raise SceneConfigError(path, f"{pre}.opacity", f"must be in [0, 1], got {kw['opacity']}")
    if kw.get("blend", "opaque") == "opaque":
        for key in ("opacity", "opacity_source"):
            if key in kw:
                raise SceneConfigError(path, f"{pre}.{key}", "has no effect without blend = "
                                       "\"over\" or \"additive\"")
    if kw.get("opacity_source") == "texture_alpha":
        if "texture" not in kw:
            raise SceneConfigError(path, f"{pre}.opacity_source", "\"texture_alpha\" needs a "
                                   "texture")
        if not texture_has_alpha(textures[kw["texture"]]):
            raise SceneConfigError(path, f"{pre}.opacity_source", "\"texture_alpha\" but the "
                                   "texture has no alpha channel (every texel opaque)")


def _meshes(path: Path, data: dict, materials: list, textures: list, by_name: dict) -> list:
    """The mesh parts, transformed; a file's own materials and textures are appended to
    ``materials`` and ``textures``."""
    parts = []
    meshes = array_of_tables(path, data, "meshes")
    if not meshes:
        raise SceneConfigError(path, "meshes", "at least one [[meshes]] entry is required")
    for i, m in enumerate(meshes):
        pre = f"meshes[{i}]"
        check_table(path, pre, m, MESH)
        if ("file" in m) == ("primitive" in m):
            raise SceneConfigError(path, pre, "give exactly one of 'file' or 'primitive'")
        mat = None
        if "material" in m:
            if m["material"] not in by_name:
                raise SceneConfigError(path, f"{pre}.material",
                                       f"unknown material {m['material']!r}; known: {sorted(by_name)}")
            mat = by_name[m["material"]]
        if "file" in m:
            f = existing_file(path, f"{pre}.file", m["file"])
            try:
                got = load_mesh_file(f, materials, textures)
            except Exception as e:  # noqa: BLE001
                raise SceneConfigError(path, f"{pre}.file", f"cannot load mesh {m['file']!r}: {e}") from None
        else:
            if mat is None:
                if not materials:
                    materials.append(Material())
                mat = 0
            got = [_primitive(path, pre, m)]
        xf = trs_matrix(m.get("translate", (0, 0, 0)), m.get("rotate_deg", (0, 0, 0)), m.get("scale", 1.0))
        motion = _motion(path, f"{pre}.motion", m["motion"]) if "motion" in m else None
        for p in got:
            p.motion = motion
            p = p.transformed(xf)
            if mat is not None:
                p.material = mat
            if "velocity" in m:
                p.velocity = np.asarray(m["velocity"], np.float64)
            parts.append(p)
    return parts


def _fps(path: Path, data: dict) -> float:
    fps = float(data.get("fps", DEFAULT_FPS))
    if not fps > 0.0:
        raise SceneConfigError(path, "fps", f"must be > 0, got {data['fps']!r}")
    return fps


# A key that only matters with another one set (nothing accepted and ignored).
MOTION_NEEDS = {"spin_axis": ("spin_deg_per_s",), "pivot": ("spin_deg_per_s", "orbit_deg_per_s"),
                "orbit_center": ("orbit_deg_per_s",), "orbit_axis": ("orbit_deg_per_s",),
                **{k: ("sway_amplitude",) for k in MOTION if k.startswith("sway_")
                   and k != "sway_amplitude"}}


def _motion(path: Path, pre: str, table) -> ObjectMotion:
    check_table(path, pre, table, MOTION)
    for key, needs in MOTION_NEEDS.items():
        if key in table and not any(table.get(n) for n in needs):
            raise SceneConfigError(path, f"{pre}.{key}", f"has no effect unless "
                                   f"{' or '.join(needs)} is set and non-zero")
    try:
        motion = ObjectMotion(**{k: tuple(v) if isinstance(v, list) else v
                                 for k, v in table.items()})
    except ValueError as e:
        key = next((k for k in table if str(e).startswith(k)), None)
        raise SceneConfigError(path, f"{pre}.{key}" if key else pre, str(e)) from None
    if not (motion.rigid or motion.sways):
        raise SceneConfigError(path, pre, "declares no motion; set spin_deg_per_s, velocity, "
                               "orbit_deg_per_s or sway_amplitude")
    return motion


def _lights(path: Path, data: dict) -> tuple[list, list, np.ndarray]:
    """(directional (direction, irradiance) pairs, point (position, intensity) pairs, ambient
    radiance RGB)."""
    directional, point, ambient = [], [], np.zeros(3)
    for i, lt in enumerate(array_of_tables(path, data, "lights")):
        pre = f"lights[{i}]"
        check_table(path, pre, lt, LIGHT, required=("type",))
        need = LIGHT_KEYS[lt["type"]]
        for k in lt:
            if k != "type" and k not in need:
                raise SceneConfigError(path, f"{pre}.{k}", f"not a key of a {lt['type']} light; "
                                       f"allowed: {', '.join(need)}")
        for k in need:
            if k not in lt:
                raise SceneConfigError(path, f"{pre}.{k}", "missing required key")
        if lt["type"] == "directional":
            if np.linalg.norm(lt["direction"]) == 0:
                raise SceneConfigError(path, f"{pre}.direction", "must not be zero")
            directional.append((lt["direction"], lt["irradiance"]))
        elif lt["type"] == "point":
            point.append((lt["position"], lt["intensity"]))
        else:
            ambient = ambient + np.asarray(rgb(lt["radiance"]))
    return directional, point, ambient


def _effects(path: Path, data: dict) -> dict:
    eff = dict(data.get("effects", {}))
    check_table(path, "effects", eff, EFFECTS)
    if "brdfs" in eff:
        bad = [b for b in eff["brdfs"] if b not in BRDF_NAMES]
        if bad:
            raise SceneConfigError(path, "effects.brdfs", f"unknown BRDF {bad[0]!r}")
        eff["brdfs"] = tuple(BRDF_NAMES[b] for b in eff["brdfs"])
    return eff


def _primitive(path, pre, m):
    kind, size, sub = m["primitive"], m.get("size"), m.get("subdivisions")
    vals = None if size is None else np.atleast_1d(np.asarray(size, np.float64))
    if kind == "plane":
        if vals is not None and vals.size not in (1, 2, 3):
            raise SceneConfigError(path, f"{pre}.size", "plane size is s or [w, d]")
        wd = (1.0, 1.0) if vals is None else (vals[0], vals[min(1, vals.size - 1)])
        n = sub or 1
        return grid_plane(wd, (n, n), tuple(m.get("uv_scale", (1.0, 1.0))))
    if "uv_scale" in m:
        raise SceneConfigError(path, f"{pre}.uv_scale", "only planes take uv_scale")
    if kind == "box":
        if vals is not None and vals.size not in (1, 3):
            raise SceneConfigError(path, f"{pre}.size", "box size is s or [w, h, d]")
        return box(tuple(np.broadcast_to(vals if vals is not None else 1.0, (3,))))
    radius = 1.0 if vals is None else float(vals[0])
    n = sub or 16
    return uv_sphere(radius, n, 2 * n)
