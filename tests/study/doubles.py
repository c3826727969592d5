"""Test doubles for the study machinery: a tiny scene, two tiny pipelines, a camera path
and NumPy metrics.

``install(monkeypatch)`` puts them in place for one test (the registry entries and backend
functions are restored afterwards), so the runner, store, cache and figures can be tested end
to end in seconds, independently of the real scenes, pipelines and metrics.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

import jaxrender.metrics
from jaxrender.pipelines import registry
from jaxrender.scene import camera_path
from jaxrender.scene.camera import look_at
from jaxrender.study import backend
from jaxrender.types import Frame, pytree_dataclass, static_field

FAKE_SCENES = ("tiny", "tiny2")
REAL_METRICS = dict(jaxrender.metrics.METRICS)  # before any test replaces them


@pytree_dataclass
class FakeScene:
    color: jax.Array  # float32[3]
    name: str = static_field(default="tiny")


@dataclass(frozen=True)
class FlatConfig(registry.RenderConfig):
    levels: int = 8
    noise: float = 0.0
    dither: bool = False
    mode: str = "nearest"
    rates: tuple = (1, 1)

    def __post_init__(self):
        if self.levels < 1:
            raise ValueError(f"levels must be >= 1, got {self.levels}")


@dataclass(frozen=True)
class RefConfig(registry.RenderConfig):
    samples: int = 4
    convergence: bool = False


def _base(scene, camera, w, h):
    x = (jnp.arange(w, dtype=jnp.float32) + 0.5) / w
    y = (jnp.arange(h, dtype=jnp.float32) + 0.5) / h
    wave = 0.5 + 0.4 * jnp.sin(6.0 * x[None, :] + 3.0 * y[:, None] + camera.eye[0])
    return wave[:, :, None] * scene.color[None, None, :]


def render_reference(scene, camera, cfg: RefConfig) -> Frame:
    """Fake ground truth: a smooth function of the pixel and the camera."""
    img = _base(scene, camera, cfg.width, cfg.height)
    return Frame(img, {"convergence_psnr": jnp.float32(80.0)}, {})


def render_flat(scene, camera, cfg: FlatConfig) -> Frame:
    """Fake pipeline: the reference quantised to ``levels`` plus a little patterned noise."""
    w, h = cfg.width, cfg.height
    img = jnp.floor(_base(scene, camera, w, h) * cfg.levels) / cfg.levels
    ix = jnp.arange(w, dtype=jnp.int32)[None, :]
    iy = jnp.arange(h, dtype=jnp.int32)[:, None]
    pattern = jnp.sin(37.0 * ix.astype(jnp.float32) + 91.0 * iy.astype(jnp.float32)
                      + 5.0 * camera.eye[0])
    img = img + cfg.noise * pattern[:, :, None]
    covered = w * h
    inv = covered * min(cfg.levels, 16) // 16
    waves = -(-inv // 32)
    level = ((ix % 4) + (iy % 4)) % 5
    counts = {
        "shade_invocations": jnp.int32(inv),
        "helper_lanes": jnp.int32(inv // 4),
        "covered_pixels": jnp.int32(covered),
        "waves": jnp.int32(waves),
        "lane_utilization": jnp.float32(inv / max(1, waves * 32)),
    }
    aux = {
        "level": level,
        "shaded": level == 0,
        "chunk_state": ((ix[:, :: 8] // 8 + iy[:: 8, :] // 8) % 3).astype(jnp.int32),
        "mip_level": (ix.astype(jnp.float32) / w + iy.astype(jnp.float32) / h),
        "sample_class": level - 1,  # tads's map: -1 uncovered, 0-4 texels shaded
        "duplicates": (level == 3).astype(jnp.int32),
    }
    return Frame(img, counts, aux)


# ------------------------------------------------------------------ NumPy metrics


def _np_metrics():
    def rmse(a, b, **_):
        return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))

    def psnr(a, b, **_):
        m = np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2)
        return float("inf") if m == 0 else float(10 * np.log10(1.0 / m))

    def ssim(a, b, **_):
        return float(1.0 - np.mean(np.abs(np.asarray(a) - np.asarray(b))))

    def flip(ref, test):
        m = np.abs(np.asarray(test) - np.asarray(ref)).mean(-1)
        return float(m.mean()), m

    def delta_e2000(a, b, **_):
        return float(100 * np.mean(np.abs(np.asarray(a) - np.asarray(b)))), None

    def temporal_error(i, r, **_):
        di, dr = np.diff(np.asarray(i), axis=0), np.diff(np.asarray(r), axis=0)
        return float(np.mean(np.abs(di - dr)))

    return dict(rmse=rmse, psnr=psnr, mssim=ssim, flip=lambda t, r, **_: flip(r, t),
                delta_e=delta_e2000, temporal_error=temporal_error)


def fake_pan(camera, frames, width, height, *, step=0.05):
    return [look_at((step * t, 0.5, 3.0), (step * t, 0.0, 0.0)) for t in range(frames)]


FAKEPAN = camera_path.PathType(fake_pan, {"step": camera_path.PathParam(float, 0.05)})


def make_cameras(scene, path, width, height):
    """The fake scenes' cameras (``static``: the fake default camera), in any process: a
    compile worker receives this function by reference, without the test's monkeypatch."""
    params = dict(path.params) if path.type == "fakepan" else {"step": 0.0}
    return fake_pan(None, path.frames, width, height, **params)


def install(monkeypatch, *, metrics: bool = True):
    """Register ``flat`` and ``reference`` (fakes), fake scenes, the ``fakepan`` path and
    (with ``metrics``) NumPy metrics for one test."""
    monkeypatch.setitem(registry.REGISTRY, "flat",
                        registry.Pipeline("flat", FlatConfig, registry.FrameStep(render_flat),
                                          description="fake: quantised"))
    monkeypatch.setitem(registry.REGISTRY, "reference",
                        registry.Pipeline("reference", RefConfig,
                                          registry.FrameStep(render_reference),
                                          description="fake: smooth ground truth"))
    colors = {"tiny": (1.0, 0.8, 0.6), "tiny2": (0.3, 0.9, 0.5)}

    def load_scene(source, params):
        return FakeScene(jnp.asarray(colors[source], jnp.float32), source)

    monkeypatch.setattr(backend, "builtin_scene_names", lambda: list(FAKE_SCENES))
    monkeypatch.setattr(backend, "builtin_scenes",
                        lambda: [(n, f"fake scene {n}") for n in FAKE_SCENES])
    monkeypatch.setattr(backend, "load_scene", load_scene)
    monkeypatch.setattr(backend, "default_camera", lambda scene: look_at((0, 0.5, 3), (0, 0, 0)))
    monkeypatch.setitem(camera_path.PATH_TYPES, "fakepan", FAKEPAN)
    monkeypatch.setattr(backend, "make_cameras", make_cameras)
    if metrics:
        for name, fn in _np_metrics().items():
            m = jaxrender.metrics.METRICS[name]
            monkeypatch.setitem(jaxrender.metrics.METRICS, name, dataclasses.replace(m, fn=fn))


# The smallest study file over the doubles, for schema tests to extend.
MINIMAL_STUDY = """
name = "t"
resolution = "24x16"
scenes = ["tiny"]
[[pipelines]]
type = "flat"
"""


def write_study(root, text, name="s.toml"):
    """``text`` (dedented) as ``root/studies/name``; returns its path."""
    import textwrap

    p = root / "studies" / name
    p.parent.mkdir(exist_ok=True)
    p.write_text(textwrap.dedent(text))
    return p
