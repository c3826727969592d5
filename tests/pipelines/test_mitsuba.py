"""The reference against an independent renderer: Mitsuba 3 (scalar_rgb, integrator `direct`).

Diffuse scenes without shadows (nothing casts a shadow that the camera can see), point and
directional lights, the same triangle arrays handed to both. Mitsuba's conventions match ours:
pixel i covers [i, i+1), centre i + 0.5, row 0 at the top, vertical field of view; its box
filter (radius 0.5) keeps every sample in its own pixel, as our box filter does. Both are
converged (k = 8 stratified cell centres here, 32 x 32 jittered strata in Mitsuba), so the
images agree to well above 45 dB in linear radiance (k = 16 adds a few dB and takes three
times as long under the suite's unoptimized compiles). On failure the two images and their
difference are written to error_output/ (gitignored).
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 (pip install mitsuba) is a test extra")

from jaxrender.pipelines.reference import ReferenceConfig, render
from jaxrender.scene import Material, Scene, look_at, make_lights
from jaxrender.scene.mesh import box, trs_matrix, uv_sphere
from jaxrender.scene.scene import build_scene

W, H = 64, 48
K = 8  # reference samples per pixel side
SPP = 1024  # Mitsuba: 32 x 32 stratified (jittered) samples per pixel
MIN_PSNR = 45.0  # dB, linear radiance, data range = the reference's maximum
ERROR_DIR = Path(__file__).resolve().parents[2] / "error_output"


@pytest.fixture(scope="module", autouse=True)
def _variant():
    mi.set_variant("scalar_rgb")


# ------------------------------------------------------------------ scenes
# Every scene has the same topology (a wall, a box, a smooth sphere, a small cube) and one
# directional plus one point light, so the three share one compiled reference program; what
# differs is where things are, their albedos and the lights' strengths and directions.


def _scene(wall_at, box_at, sphere_at, cube_at, albedos, sun, point, eye, target,
           fov=40.0) -> tuple[Scene, object]:
    parts = [
        box((6.0, 4.0, 0.2), material=0).transformed(trs_matrix(wall_at)),
        box((0.9, 0.9, 0.9), material=1).transformed(trs_matrix(box_at, (0, 35, 0))),
        uv_sphere(0.6, 16, 32, material=2).transformed(trs_matrix(sphere_at)),
        box((0.4, 0.4, 0.4), material=3).transformed(trs_matrix(cube_at, (20, 45, 10))),
    ]
    mats = [Material(f"m{i}", albedo=a) for i, a in enumerate(albedos)]
    cam = look_at(eye, target, fov_y_deg=fov, near=0.1, far=50.0)
    lights = make_lights([sun], [point], ambient=0.0)
    return build_scene(parts, mats, [], lights, cam, name="mitsuba_check"), cam


def _scenes():
    eye = (0.3, 1.2, 5.0)
    off = (0.0, 0.0, 40.0)  # behind the camera, out of view
    return {
        # A wall behind three objects, lit by a point light at the eye: every shadow falls
        # exactly behind the object that casts it, hidden from the camera.
        "point_at_eye": _scene(
            (0, 1, -2), (-1.2, 0.6, 0), (0.4, 0.8, 0.3), (1.5, 1.6, -0.5),
            [(0.7, 0.7, 0.7), (0.8, 0.3, 0.2), (0.2, 0.5, 0.8), (0.9, 0.9, 0.2)],
            ((0, 1, 0), 0.0), (eye, 30.0), eye, (0, 0.8, 0)),
        # Three convex objects side by side, no wall, one directional light from the upper
        # left front: self-shadowing of a convex body is its own back-facing side.
        "directional": _scene(
            off, (-1.3, 0.5, 0), (0.0, 0.9, 0), (1.3, 0.6, 0.2),
            [(0.5, 0.5, 0.5), (0.3, 0.8, 0.3), (0.9, 0.6, 0.4), (0.6, 0.2, 0.7)],
            ((-0.5, 0.7, 0.6), (2.0, 1.8, 1.5)), ((0, 0, 60), 0.0), eye, (0, 0.7, 0)),
        # Both kinds at once on the convex objects, seen from the side; the point light is
        # close to the sphere, so its 1/d^2 falloff varies strongly across it.
        "point_and_directional": _scene(
            off, (1.3, 0.4, -0.6), (0.5, 0.7, 0.2), (-0.2, 1.5, -0.8),
            [(0.5, 0.5, 0.5), (0.8, 0.8, 0.8), (0.9, 0.9, 0.9), (0.4, 0.6, 0.9)],
            ((0.8, 0.5, 0.3), (0.6, 0.8, 1.0)), ((1.6, 1.6, 1.6), (6.0, 4.0, 3.0)),
            (2.5, 2.0, 4.0), (0, 0.7, 0), fov=35.0),
    }


# ------------------------------------------------------------------ the same scene in Mitsuba


def _rgb(v):
    return {"type": "rgb", "value": [float(x) for x in np.broadcast_to(v, (3,))]}


def _mitsuba_image(scene: Scene, camera) -> np.ndarray:
    pos = np.asarray(scene.positions, np.float32)
    nrm = np.asarray(scene.normals, np.float32)
    faces = np.asarray(scene.faces, np.uint32)
    tri_mat = np.asarray(scene.tri_material)
    albedo = np.asarray(scene.materials.albedo, np.float64)
    rot = np.asarray(camera.rotation, np.float64)  # rows: right, up, backward
    eye = np.asarray(camera.eye, np.float64)
    fov_deg = float(np.rad2deg(float(camera.fov_y)))
    d = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        "sensor": {
            "type": "perspective",
            "fov": fov_deg,
            "fov_axis": "y",
            "near_clip": float(camera.near),
            "far_clip": float(camera.far),
            # look_at builds a rigid transform: no scale in the camera's matrix.
            "to_world": mi.ScalarTransform4f().look_at(
                origin=eye.tolist(), target=(eye - rot[2]).tolist(), up=rot[1].tolist()),
            "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"},
                     "pixel_format": "rgb", "component_format": "float32"},
            "sampler": {"type": "stratified", "sample_count": SPP, "seed": 7},
        },
    }
    for m in np.unique(tri_mat):
        f = faces[tri_mat == m]
        props = mi.Properties()
        # two-sided like our shading, which orients normals towards the viewer
        props["bsdf"] = mi.load_dict({"type": "twosided", "bsdf": {
            "type": "diffuse", "reflectance": _rgb(albedo[m])}})
        mesh = mi.Mesh(f"mesh{m}", len(pos), len(f), props, has_vertex_normals=True)
        params = mi.traverse(mesh)
        floats, uints = type(params["vertex_positions"]), type(params["faces"])
        params["vertex_positions"] = floats(pos.ravel())
        params["vertex_normals"] = floats(nrm.ravel())
        params["faces"] = uints(f.ravel())
        params.update()
        d[f"mesh{m}"] = mesh
    lt = scene.lights
    for i, (to_l, e) in enumerate(zip(np.asarray(lt.dir_to_light), np.asarray(lt.dir_irradiance))):
        if np.any(e > 0):  # Mitsuba's `direction` points from the light into the scene
            d[f"sun{i}"] = {"type": "directional", "direction": (-to_l).tolist(),
                            "irradiance": _rgb(e)}
    for i, (p, inten) in enumerate(zip(np.asarray(lt.point_position),
                                       np.asarray(lt.point_intensity))):
        if np.any(inten > 0):
            d[f"point{i}"] = {"type": "point", "position": p.tolist(), "intensity": _rgb(inten)}
    img = mi.render(mi.load_dict(d), spp=SPP)
    return np.asarray(img, np.float64)[..., :3]


def _psnr(ref: np.ndarray, img: np.ndarray) -> float:
    peak = float(ref.max())
    mse = float(np.mean((ref - img) ** 2))
    return float("inf") if mse == 0 else 10.0 * np.log10(peak * peak / mse)


def _write_failure(name: str, ours: np.ndarray, theirs: np.ndarray) -> Path:
    ERROR_DIR.mkdir(exist_ok=True)
    stem = ERROR_DIR / f"mitsuba_{name}"
    for tag, img in (("reference", ours), ("mitsuba", theirs), ("diff", np.abs(ours - theirs))):
        mi.Bitmap(np.ascontiguousarray(img, np.float32)).write(f"{stem}_{tag}.exr")
        np.save(f"{stem}_{tag}.npy", img)
    return stem


@pytest.mark.parametrize("name", ["point_at_eye", "directional", "point_and_directional"])
def test_reference_matches_mitsuba(name):
    scene, cam = _scenes()[name]
    ours = np.asarray(render(scene, cam, ReferenceConfig(width=W, height=H, k=K)).image,
                      np.float64)
    theirs = _mitsuba_image(scene, cam)
    assert ours.shape == theirs.shape == (H, W, 3)
    assert ours.max() > 0.05, f"{name}: the reference image is (nearly) black"
    p = _psnr(ours, theirs)
    if not p >= MIN_PSNR:
        stem = _write_failure(name, ours, theirs)
        pytest.fail(f"{name}: PSNR(reference, Mitsuba) = {p:.2f} dB < {MIN_PSNR} dB "
                    f"(linear, data range {ours.max():.3f}); images written to {stem}_*.exr")


def test_mitsuba_scenes_share_one_program():
    """The three scenes have one topology, so a single compile serves all of them."""
    shapes = {name: tuple(jnp.shape(a) for a in (s.positions, s.faces, s.lights.dir_to_light,
                                                 s.lights.point_position))
              for name, (s, _) in _scenes().items()}
    assert len(set(shapes.values())) == 1, shapes
