"""Texture-aligned deferred shading (TADS), static part: one virtual texture that addresses the
level-0 shade sheet of every object, so that a pixel's "physical position" alone says which
texels its filter reads.

The objects' sheets are object_space's (``os_sheet.build_sheet``: charts, power-of-two sheets,
MIP chains, triangle-id maps), for the objects with a face that does not blend only: blended
faces are drawn by the forward transparent pass and never shaded into a sheet, so an object
whose faces all blend gets no chart, no sheet and no place here. Their level-0 squares are
packed into one virtual texture of at most ``VIRTUAL_SIZE`` texels a side, largest first in
Morton order (power-of-two squares taken largest first tile a Morton curve without gaps, each
one aligned to its own size). A page table of 8x8-texel pages names the object under each
page; the MIP levels of an object are addressed through the object (its sheet's ``obj_base``),
as a virtual-texture page table would.

A physical position is an int32 per axis: level-0 virtual texels in fixed point with
``SUBTEXEL_BITS`` = 8 fractional bits (14 integer bits for 16384 texels), the precision of the
8-bit bilinear fractions that the filter uses anyway (``os_marking.FRACTION``), so the stored
position reproduces the filter of the exact one (tests/pipelines/test_tads.py checks it).

Unsupported inputs are refused on the host, naming the object: a chart that is not usable
(non-finite, outside the unit square, or a triangle of non-zero world area flattened to no
chart area) and level-0 sheets whose total area exceeds the virtual texture (blended-only
objects have neither, so they are never the cause).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxrender.pipelines.os_sheet import CHUNK, ShadeSheet, build_sheet
from jaxrender.pipelines.os_texels import flattened, tri_area2
from jaxrender.types import Array, pytree_dataclass, static_field

VIRTUAL_BITS = 14
VIRTUAL_SIZE = 1 << VIRTUAL_BITS  # texels a side of the virtual texture
SUBTEXEL_BITS = 8  # fractional bits of a physical position
SUBTEXEL = 1 << SUBTEXEL_BITS
PAGE = CHUNK  # texels a side of a page of the page table


@pytree_dataclass
class TadsStatic:
    """The scene's sheets (``sheet``), each object's level-0 origin in the virtual texture
    ``origin`` int32[O, 2] (x, y texels) and the page table ``page_object`` int32[PH * PW]
    (object under each 8x8 page, -1 none) of the used part of the virtual texture, PW pages
    wide (``pages_wide``, static)."""

    sheet: ShadeSheet
    origin: Array
    page_object: Array
    pages_wide: int = static_field(default=1)


def object_label(scene, o: int, n_tris: int) -> str:
    return f"object {o} of scene {scene.name!r} ({n_tris} triangles)"


def check_charts(scene, sheet: ShadeSheet) -> None:
    """Raise ValueError naming the first object whose chart cannot address its surface (an
    object without a sheet, ``obj_res`` 0, has no chart to check: nothing reads one)."""
    corner = np.asarray(sheet.corner_st, np.float64)
    pos = np.asarray(scene.positions, np.float64)[np.asarray(scene.faces)]
    obj = np.asarray(scene.tri_object)
    world = tri_area2(pos)
    chart = tri_area2(corner)
    res = np.asarray(sheet.obj_res)
    for o in range(int(obj.max(initial=-1)) + 1):
        if res[o] == 0:
            continue
        sel = obj == o
        c = corner[sel]
        why = None
        if not np.all(np.isfinite(c)):
            why = "non-finite chart coordinates"
        elif c.size and (c.min() < 0.0 or c.max() > 1.0):
            why = "chart coordinates outside [0, 1]^2"
        elif np.any(flattened(chart[sel], world[sel])):
            why = "a triangle of non-zero area has no chart area"
        if why:
            raise ValueError(f"tads: {object_label(scene, o, int(sel.sum()))} has no usable "
                             f"UV chart ({why}); give it unique UVs or let xatlas chart it")


def _morton_xy(index: int) -> tuple[int, int]:
    x = y = 0
    for b in range(VIRTUAL_BITS):
        x |= ((index >> (2 * b)) & 1) << b
        y |= ((index >> (2 * b + 1)) & 1) << b
    return x, y


def pack_virtual(res: list[int], labels: list[str], size: int = VIRTUAL_SIZE) -> np.ndarray:
    """Origins int64[O, 2] of power-of-two squares of sides ``res`` in a ``size``^2 virtual
    texture, largest first along a Morton curve; raises naming the first object past its end.
    A side of 0 (an object without a sheet) takes no place; its origin (0, 0) is never read."""
    origin = np.zeros((len(res), 2), np.int64)
    at = 0
    for o in sorted(range(len(res)), key=lambda k: (-res[k], k)):
        if res[o] == 0:
            continue
        if at + res[o] ** 2 > size * size:
            raise ValueError(f"tads: {labels[o]}'s {res[o]}^2 sheet does not fit the "
                             f"{size}^2 virtual texture (the sheets need "
                             f"{sum(r * r for r in res)} texels); lower sheet_resolution "
                             f"or texel_density")
        origin[o] = _morton_xy(at)
        at += res[o] ** 2
    return origin


def build_static(scene, cfg) -> TadsStatic:
    """Sheets, virtual-texture origins and page table of ``scene`` (host side); objects whose
    faces all blend get no sheet."""
    sheet = build_sheet(scene, cfg, opaque_only=True)
    check_charts(scene, sheet)
    res = [int(r) for r in np.asarray(sheet.obj_res)]
    obj = np.asarray(scene.tri_object)
    labels = [object_label(scene, o, int(np.sum(obj == o))) for o in range(len(res))]
    origin = pack_virtual(res, labels)
    ext = np.max(origin + np.asarray(res)[:, None], axis=0, initial=PAGE)
    pw, ph = int(ext[0]) // PAGE, int(ext[1]) // PAGE
    table = np.full((ph, pw), -1, np.int32)
    for o, r in enumerate(res):
        x, y = origin[o] // PAGE
        table[y:y + r // PAGE, x:x + r // PAGE] = o
    return TadsStatic(sheet, jnp.asarray(origin.astype(np.int32)),
                      jnp.asarray(table.reshape(-1)), pw)


__all__ = ["PAGE", "SUBTEXEL", "SUBTEXEL_BITS", "TadsStatic", "VIRTUAL_BITS", "VIRTUAL_SIZE",
           "build_static", "check_charts", "pack_virtual"]
