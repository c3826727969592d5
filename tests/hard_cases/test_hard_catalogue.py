"""The hard-case catalogue itself: every case states what it stresses and what must hold, keeps
the common layout (one compile per pipeline), really is as hard as it says, and its geometric
promises hold in the rasterizer (coverage and ties; exactness of the raster against the NumPy
reference is pinned in tests/raster/test_exact.py and test_robust.py, not repeated here)."""

import numpy as np
import pytest

from jaxrender.raster import fragments, rasterize
from jaxrender.scene.camera import world_to_clip
from jaxrender.scene.hard_cases import (CASES, EFFECTS, N_FACES, N_VERTS, RESOLUTION,
                                        hard_case_scene, list_hard_cases)

W, H = RESOLUTION
BARY_TOL = 1e-5  # barycentric sums after the rasterizer's clamp-and-renormalise


def _vis(name):
    s = hard_case_scene(name)
    return s, rasterize(np.asarray(s.positions), np.asarray(s.faces), s.camera, W, H)


def _screen_area_px(scene, faces):
    """Signed-area magnitudes in pixels^2 of the given faces (float64, after projection)."""
    clip = np.asarray(world_to_clip(scene.positions, scene.camera, W / H), np.float64)
    ndc = clip[:, :2] / clip[:, 3:4]
    xy = (ndc + 1.0) * 0.5 * np.array([W, H])
    p = xy[faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def test_every_case_states_what_it_stresses_what_must_hold_and_a_bound():
    assert len(CASES) >= 20
    for name, case in CASES.items():
        assert name.startswith("hard_") and case.doc, name
        assert "must hold" in case.doc.lower(), f"{name}: docstring must say what must hold"
        assert case.bound >= 0.0 and np.isfinite(case.bound), name
    assert [n for n, _ in list_hard_cases()] == list(CASES)


def test_every_case_has_the_common_layout():
    # Same shapes and static effects: one compile per (pipeline, resolution) serves them all.
    first = None
    for name in CASES:
        s = hard_case_scene(name)
        shapes = [a.shape for a in (s.positions, s.faces, s.normals, s.uvs, s.materials.albedo,
                                    s.textures.atlas, s.lights.point_position,
                                    s.lights.dir_to_light)]
        assert s.positions.shape == (N_VERTS, 3) and s.faces.shape == (N_FACES, 3), name
        assert s.effects == EFFECTS, name
        first = first or shapes
        assert shapes == first, name
        for leaf in (s.positions, s.normals, s.uvs, s.tangents):
            assert np.all(np.isfinite(np.asarray(leaf))), f"{name}: non-finite scene input"


def test_the_cases_are_as_hard_as_they_claim():
    s = hard_case_scene("hard_sliver")
    p = np.asarray(s.positions, np.float64)[np.asarray(s.faces)]
    edges = np.linalg.norm(p - np.roll(p, 1, axis=1), axis=-1)
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=-1)
    real = area2 > 0
    aspect = edges.max(-1)[real] ** 2 / area2[real]  # longest edge / height to it
    assert (aspect >= 1e6 * 0.99).sum() >= 200, "slivers of aspect >= 1e6"

    s = hard_case_scene("hard_subpixel")
    mat = np.asarray(s.tri_material)
    tiny = np.nonzero(mat == 1)[0][:400]  # the rest is zero-area padding
    area = _screen_area_px(s, np.asarray(s.faces)[tiny])
    np.testing.assert_allclose(area, 1e-4, rtol=0.35, err_msg="sub-pixel area 1e-4 px^2")

    s = hard_case_scene("hard_degenerate")
    tris = np.asarray(s.faces)[np.asarray(s.tri_material) == 1]
    assert np.all(_screen_area_px(s, tris) < 1e-5), "degenerate triangles have no area"

    assert np.rad2deg(float(hard_case_scene("hard_fov_1").camera.fov_y)) == pytest.approx(1.0)
    assert np.rad2deg(float(hard_case_scene("hard_fov_170").camera.fov_y)) == pytest.approx(170.0)
    assert float(np.abs(hard_case_scene("hard_far_1e7").positions).max()) >= 1e7
    s = hard_case_scene("hard_w_near_zero")
    view_z = np.asarray(s.positions)[:, 2] - float(s.camera.eye[2])
    assert np.min(np.abs(view_z)) == 0.0 and np.any(np.abs(view_z[view_z != 0]) <= 1e-7)
    assert float(hard_case_scene("hard_phong_1e6").materials.shininess[1]) == 1e6
    n = np.linalg.norm(np.asarray(hard_case_scene("hard_bad_normals").normals, np.float64), axis=-1)
    assert (n == 0).any() and (n > 1e14).any() and ((n > 0) & (n < 1e-29)).any()


def test_degenerate_triangles_cover_nothing():
    s, vis = _vis("hard_degenerate")
    ids = np.asarray(vis.tri_id)
    assert np.all(np.asarray(s.tri_material)[ids] == 0), "only the wall may be visible"
    assert np.all(ids >= 0)


def test_sliver_fan_is_watertight_and_single_layer():
    s = hard_case_scene("hard_sliver")
    clip = world_to_clip(s.positions, s.camera, W / H)
    fr = fragments(np.asarray(clip), np.asarray(s.faces), W, H, capacity=8 * W * H)
    valid = np.asarray(fr.valid)
    tri, pix = np.asarray(fr.tri)[valid], np.asarray(fr.pixel)[valid]
    fan = np.asarray(s.tri_object)[tri] == 1
    count = np.bincount(pix[fan], minlength=W * H).reshape(H, W)
    assert count.max() <= 1, "a fan sample covered twice"
    # Pixel centres well inside the fan's disc (radius 1.2 at z = 0: about 6.6 px).
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    inside = np.hypot(xx - W / 2, yy - H / 2) < 5.5
    assert np.all(count[inside] == 1), "the wall shows through the fan"


def _coplanar():
    s, vis = _vis("hard_coplanar")
    clip = world_to_clip(s.positions, s.camera, W / H)
    fr = fragments(np.asarray(clip), np.asarray(s.faces), W, H, capacity=8 * W * H)
    valid = np.asarray(fr.valid)
    tri, pix = np.asarray(fr.tri)[valid], np.asarray(fr.pixel)[valid]
    front = np.asarray(s.tri_object)[tri] > 0  # the three coplanar quads
    lowest = np.full(W * H, np.iinfo(np.int32).max)
    np.minimum.at(lowest, pix[front], tri[front])
    has = lowest < np.iinfo(np.int32).max
    return s, np.asarray(vis.tri_id).reshape(-1), lowest, has


def test_coplanar_overlap_has_a_deterministic_winner():
    s, ids, lowest, has = _coplanar()
    obj = np.asarray(s.tri_object)
    assert np.all(obj[ids[has]] > 0), "the wall behind never wins"
    assert not np.any(obj[ids[has]] == 3), "quad c (an exact copy of a) never beats a"
    _, again, _, _ = _coplanar()
    np.testing.assert_array_equal(ids, again, err_msg="rerun")


def test_screen_parallel_coplanar_overlap_goes_to_the_lowest_index():
    _, ids, lowest, has = _coplanar()
    np.testing.assert_array_equal(ids[has], lowest[has], err_msg="tie winner")


@pytest.mark.parametrize("name", ["hard_near_plane", "hard_w_near_zero", "hard_fov_170",
                                  "hard_grazing", "hard_magnify", "hard_far_1e7"])
def test_visibility_of_extreme_views_is_finite_with_valid_barycentrics(name):
    _, vis = _vis(name)
    for f in ("depth", "bary", "dbary_dx", "dbary_dy"):
        assert np.all(np.isfinite(np.asarray(getattr(vis, f)))), f"{name}: {f}"
    cov = np.asarray(vis.tri_id) >= 0
    assert cov.any(), f"{name}: something must be visible"
    b = np.asarray(vis.bary)[cov]
    assert (b >= 0).all() and (b <= 1).all(), name
    np.testing.assert_allclose(b.sum(-1), 1.0, atol=BARY_TOL, err_msg=name)


def test_nothing_behind_the_eye_is_drawn():
    s, vis = _vis("hard_empty")
    assert np.all(np.asarray(vis.tri_id) == -1)
    s, vis = _vis("hard_near_plane")
    ids = np.asarray(vis.tri_id)
    # The ceiling (y = 0.5) is above the eye: only the image's upper half may show it.
    first_tri = int(np.argmax(np.asarray(s.tri_object) == 2))
    ceiling = ids == first_tri
    assert ceiling[: H // 2].any() and not ceiling[H // 2:].any()


@pytest.mark.parametrize("name", ["hard_far_1e5", "hard_far_1e7"])
def test_far_coordinates_see_what_the_origin_sees(name):
    # Camera-relative transforms: the same (scaled) scene 1e5 / 1e7 away gives nearly the same
    # ids as at the origin (float32 rounding of the positions moves edges by < 0.1 px).
    _, near = _vis("hard_far_origin")
    _, far = _vis(name)
    same = np.mean(np.asarray(near.tri_id) == np.asarray(far.tri_id))
    assert same > 0.97, same
