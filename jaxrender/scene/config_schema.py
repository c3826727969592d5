"""The scene TOML schema: what each table may hold and the checks of its values, with the
error every check raises (naming the file and the key). ``config`` reads scene files with it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jaxrender.scene.effects import (BLEND_NAMES, BRDF_NAMES, EFFECT_FIELDS, OPACITY_SOURCES,
                                     PROCEDURAL_NAMES)


class SceneConfigError(ValueError):
    """A malformed scene file; the message names the file and the key."""

    def __init__(self, path, key, problem):
        self.path, self.key = str(path), key
        super().__init__(f"{path}: key {key!r}: {problem}")


# ---------------------------------------------------------------- value checkers

def _num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _vec(n):
    def check(v):
        return isinstance(v, list) and len(v) == n and all(_num(x) for x in v)
    check.__doc__ = f"a list of {n} numbers"
    return check


def _num_or_vec(n):
    vec = _vec(n)

    def check(v):
        return _num(v) or vec(v)
    check.__doc__ = f"a number or a list of {n} numbers"
    return check


def _of(t, doc):
    def check(v):
        return isinstance(v, t) and not (t in (int, (int, float)) and isinstance(v, bool))
    check.__doc__ = doc
    return check


def _choice(names):
    def check(v):
        return isinstance(v, str) and v in names
    check.__doc__ = f"one of {sorted(names)}"
    return check


NUM, INT, STR, BOOL = (_of((int, float), "a number"), _of(int, "an integer"),
                       _of(str, "a string"), _of(bool, "a boolean"))
VEC3 = _vec(3)

TOP = {"base": STR, "name": STR, "description": STR, "texture_resolution": INT, "shadows": BOOL,
       "fps": NUM,
       "camera": None, "materials": None, "meshes": None, "lights": None, "effects": None}
CAMERA = {"eye": VEC3, "target": VEC3, "up": VEC3, "fov_y_deg": NUM, "near": NUM, "far": NUM}
MATERIAL = {"name": STR, "albedo": VEC3, "specular": VEC3, "shininess": NUM, "roughness": NUM,
            "brdf": _choice(BRDF_NAMES), "texture": STR, "normal_map": STR, "alpha": NUM,
            "alpha_tested": BOOL, "alpha_cutoff": NUM, "emissive": VEC3,
            "procedural": _choice(PROCEDURAL_NAMES), "stripe_resolution": NUM,
            "blend": _choice(BLEND_NAMES), "opacity": NUM,
            "opacity_source": _choice(set(OPACITY_SOURCES))}
def _size(v):
    return _num(v) or (isinstance(v, list) and len(v) in (2, 3) and all(_num(x) for x in v))


_size.__doc__ = "a number or a list of 2 or 3 numbers"
MESH = {"file": STR, "primitive": _choice({"plane", "box", "sphere"}), "size": _size,
        "subdivisions": INT, "uv_scale": _vec(2), "material": STR, "translate": VEC3,
        "rotate_deg": VEC3, "scale": _num_or_vec(3), "velocity": VEC3, "motion": None}
MOTION = {"spin_axis": VEC3, "spin_deg_per_s": NUM, "pivot": VEC3, "velocity": VEC3,
          "orbit_center": VEC3, "orbit_axis": VEC3, "orbit_deg_per_s": NUM,
          "sway_amplitude": NUM, "sway_direction": VEC3, "sway_frequency_hz": NUM,
          "sway_wavelength": NUM, "sway_height": NUM, "sway_exponent": NUM, "sway_base": NUM}
LIGHT = {"type": _choice({"directional", "point", "ambient"}), "direction": VEC3,
         "irradiance": _num_or_vec(3), "position": VEC3, "intensity": _num_or_vec(3),
         "radiance": _num_or_vec(3)}
LIGHT_KEYS = {"directional": ("direction", "irradiance"), "point": ("position", "intensity"),
              "ambient": ("radiance",)}
EFFECTS = {k: (BOOL if t in (bool, "bool") else INT if t in (int, "int") else
               NUM if t in (float, "float") else _of(list, "a list of BRDF names"))
           for k, t in EFFECT_FIELDS.items()}


def check_table(path, prefix, table, schema, required=()):
    if not isinstance(table, dict):
        raise SceneConfigError(path, prefix, "must be a table")
    for key, value in table.items():
        full = f"{prefix}.{key}" if prefix else key
        if key not in schema:
            raise SceneConfigError(path, full, f"unknown key; allowed: {', '.join(sorted(schema))}")
        check = schema[key]
        if check is not None and not check(value):
            raise SceneConfigError(path, full, f"must be {check.__doc__}, got {value!r}")
    for key in required:
        if key not in table:
            raise SceneConfigError(path, f"{prefix}.{key}" if prefix else key, "missing required key")


def array_of_tables(path, data, key):
    items = data.get(key, [])
    if not isinstance(items, list) or not all(isinstance(t, dict) for t in items):
        raise SceneConfigError(path, key, "must be an array of tables ([[%s]])" % key)
    return items


def existing_file(path, key, name):
    f = (Path(path).parent / name).resolve()
    if not f.is_file():
        raise SceneConfigError(path, key, f"file {name!r} not found (looked for {f})")
    return f


def rgb(v):
    return tuple(float(x) for x in np.broadcast_to(np.asarray(v, np.float64), (3,)))
