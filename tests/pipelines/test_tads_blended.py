"""TADS and blended objects: an object whose faces all blend is drawn by the forward transparent
pass and never shaded into the shade texture, so it gets no chart, no sheet and no place in the
virtual texture; it is neither counted in ``shade_texture_bytes`` nor a reason to refuse a scene.
Object space shades blended surfaces into its store (os_transparency), so it keeps their sheets.

The scenes are the transparency tests' quads (tests/pipelines/transparent_scenes.py): an opaque
background quad (object 0) and blended quads in front of it (objects 1, 2, ...).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from jaxrender.pipelines import get_pipeline, make_config
from jaxrender.pipelines import tads, tads_layout
from jaxrender.pipelines.object_space import ObjectSpaceConfig
from jaxrender.pipelines.os_sheet import LANES, build_sheet
from jaxrender.scene import builtin
from jaxrender.scene.lights import make_lights
from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import MeshPart
from jaxrender.scene.scene import build_scene
from tests.pipelines.transparent_scenes import BACKGROUND, TWO, layered_quads, over, quad

W, H = 32, 18
MIDDLE = (slice(7, 11), slice(13, 19))  # pixels inside every quad (test_transparency's)
TOL = 2e-6  # float32 rounding of a few blends
RES = 16
# Hand-worked: a 16^2 sheet and its MIP chain down to one 8x8 chunk: 16^2 + 8^2 texels, each
# a float32 RGB colour and an int32 frame counter in TADS's shade texture.
SHEET_TEXELS = RES * RES + 8 * 8
TEXEL_BYTES = tads.TEXEL_BYTES + tads.COUNTER_BYTES


def _render(scene, **params):
    cfg = make_config("tads", width=W, height=H, **params)
    return get_pipeline("tads").render(scene, scene.camera, cfg)


def test_blended_only_objects_get_no_texels_and_are_not_counted():
    scene = layered_quads(TWO)  # background + two blended quads: 3 objects, 1 with a sheet
    f = _render(scene, sheet_resolution=RES)
    assert float(f.counts["shade_texture_bytes"]) == 1 * SHEET_TEXELS * TEXEL_BYTES
    static = tads.prepare(scene, tads.TadsConfig(sheet_resolution=RES))
    assert static.sheet.n_chunks * LANES == SHEET_TEXELS
    # The blended quads are still drawn, over the background's filtered texels.
    assert int(f.counts["transparent_layers_max"]) == 2
    got = np.asarray(f.image)[MIDDLE].reshape(-1, 3)
    want = over([(c, a, b) for c, a, b, _ in sorted(TWO, key=lambda lay: lay[3])], BACKGROUND)
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), atol=TOL, rtol=0)
    # Object space shades blended surfaces into its store: every object keeps its sheet.
    sheet = build_sheet(scene, ObjectSpaceConfig(sheet_resolution=RES))
    assert sheet.n_chunks * LANES == 3 * SHEET_TEXELS


def test_an_object_with_one_opaque_face_keeps_its_sheet():
    # Quad 1 is mixed: its first triangle opaque (the background's material), its second
    # blended; quad 2 blends throughout.
    camera = layered_quads(TWO).camera
    mixed = build_scene([quad(-2.0, 0, size=(8.0, 8.0)), _with_material(quad(0.5, 1), [0, 1]),
                         quad(0.0, 2)], _materials(), [], make_lights([], ambient=1.0), camera,
                        name="mixed")
    static = tads.prepare(mixed, tads.TadsConfig(sheet_resolution=RES))
    assert np.asarray(static.sheet.obj_res).tolist() == [RES, RES, 0]
    assert static.sheet.sources[2] == "none"


def test_an_all_blended_scene_counts_no_texels_and_matches_deferred():
    scene = layered_quads(TWO, background=False)
    f = _render(scene, sheet_resolution=RES)
    assert float(f.counts["shade_texture_bytes"]) == 0.0
    assert int(f.counts["texels_shaded"]) == 0 and int(f.counts["overflow"]) == 0
    d = get_pipeline("deferred").render(scene, scene.camera,
                                        make_config("deferred", width=W, height=H))
    np.testing.assert_allclose(np.asarray(f.image), np.asarray(d.image), atol=TOL, rtol=0)


def test_a_blended_object_without_a_usable_chart_is_not_refused():
    # One of the sliver fan's needles has no chart area: TADS refuses the fan as an opaque
    # object (naming it) and renders it as a blended one.
    opaque, blended = (_sliver_scene(blend) for blend in ("opaque", "over"))
    with pytest.raises(ValueError, match="object 1 of scene 'slivers' .* has no usable UV chart"):
        tads.prepare(opaque, tads.TadsConfig(sheet_resolution=RES))
    f = _render(blended, sheet_resolution=RES)
    assert int(f.counts["overflow"]) == 0 and int(f.counts["transparent_invocations"]) > 0
    assert float(f.counts["shade_texture_bytes"]) == 1 * SHEET_TEXELS * TEXEL_BYTES


def test_blended_sheets_do_not_fill_the_virtual_texture(monkeypatch):
    # A virtual texture of 16^2 texels holds the background's 16^2 sheet and nothing more: the
    # scene fits with its quads blended and is refused with one of them opaque.
    monkeypatch.setattr(tads_layout, "pack_virtual",
                        functools.partial(tads_layout.pack_virtual, size=RES))
    cfg = tads.TadsConfig(sheet_resolution=RES)
    tads.prepare(layered_quads(TWO), cfg)
    one_opaque = [TWO[0], (TWO[1][0], 1.0, "opaque", TWO[1][3])]
    with pytest.raises(ValueError, match="does not fit the 16\\^2 virtual texture"):
        tads.prepare(layered_quads(one_opaque), cfg)


def _materials() -> list[Material]:
    """layered_quads(TWO)'s materials: the background's, then the two blended layers'."""
    return [Material("bg", albedo=BACKGROUND),
            *(Material(f"layer{i}", albedo=c, blend=b, opacity=a)
              for i, (c, a, b, _) in enumerate(TWO))]


def _with_material(part: MeshPart, per_face) -> MeshPart:
    return MeshPart(part.positions, part.faces, part.normals, part.uvs,
                    material=np.asarray(per_face))


def _sliver_scene(blend: str):
    """The built-in sliver scene's fan (its needle and zero-area triangles), blended or not, in
    front of a small opaque quad. Its chart fails check_charts on one needle whose chart area
    rounds to 0 in float32 while its world area (3e-8) is above 1e-9 of the fan's largest
    triangle."""
    s = builtin.sliver()
    fan = MeshPart(np.asarray(s.positions, np.float64), np.asarray(s.faces),
                   np.asarray(s.normals), np.asarray(s.uvs), material=1)
    alpha = {"opaque": 1.0, "over": 0.5}[blend]
    mats = [Material("bg", albedo=BACKGROUND),
            Material("fan", albedo=(0.7, 0.7, 0.2), blend=blend, opacity=alpha)]
    return build_scene([quad(-0.5, 0, size=(1.0, 1.0)), fan], mats, [],
                       make_lights([], ambient=1.0), s.camera, name="slivers")
