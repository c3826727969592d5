"""The hard-case catalogue: scenes built to break a renderer's numerics.

Every case is a generator ``fn(**size_params) -> Scene`` (default camera included) whose
docstring says what it stresses and what must hold, registered with its error bound: the
largest display-referred RMSE (``metrics.to_display``, then RMSE) any pipeline may have against
the reference pipeline at the case's resolution (``HardCase.bound``). Beyond the bound, every
case must give, in every pipeline: no NaN or Inf in the image, the counts or the metrics, and a
bitwise-identical image on a rerun (CPU).

All scenes share one layout (``hard_layout``) so that one compile per (pipeline, resolution)
serves the whole catalogue; the cases themselves are in ``hard_geometry`` and ``hard_shading``.
The camera is traced, so fov 1 and fov 170 degrees and eyes at 1e7 do not recompile either.

Cases not expressible as scenes: the metric inputs (constant, black, identical, HDR 1e4) are in
``metric_cases()``; the rasterizer's own random-triangle invariants are property tests
(tests/hard_cases/test_hard_raster_props.py), and tests/raster/test_robust.py already pins the
raster-only hard cases (near plane, far coordinates, slivers, ties, non-finite vertices).

Names are ``hard_<case>``, as a study names them once the scene loader knows them (see
``HARD_SCENES``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from jaxrender.scene.hard_geometry import (coplanar, degenerate, far_1e5, far_1e7, far_origin,
                                           fov_1, fov_170, grazing, near_plane, sliver,
                                           subpixel, w_near_zero)
from jaxrender.scene.hard_layout import (EFFECTS, N_FACES, N_MATERIALS, N_VERTS, RESOLUTION,
                                         SCENE_DESCRIPTION, SCENE_NAME, TEXTURE_RES)
from jaxrender.scene.hard_shading import (bad_normals, empty, flat, magnify, minify, noise,
                                          phong_1e4, phong_1e6, tiny_image, zero_area_uv)
from jaxrender.scene.scene import Scene

__all__ = ["CASES", "EFFECTS", "HARD_SCENES", "HardCase", "N_FACES", "N_MATERIALS", "N_VERTS",
           "RESOLUTION", "SCENE_DESCRIPTION", "SCENE_NAME", "TEXTURE_RES", "hard_case_scene",
           "list_hard_cases", "metric_cases"]

# ------------------------------------------------------------------ the catalogue


@dataclass(frozen=True)
class HardCase:
    """name: ``hard_<case>``; build: the generator; bound: the largest display RMSE against the
    reference any pipeline may have; resolutions: the (width, height) it is rendered at;
    constant: the image must equal one colour everywhere (within 1e-6) in every pipeline;
    empty: nothing is visible (image 0, no shading)."""

    name: str
    build: Callable[..., Scene]
    bound: float
    resolutions: tuple = (RESOLUTION,)
    constant: bool = False
    empty: bool = False

    @property
    def doc(self) -> str:
        return (self.build.__doc__ or "").strip()


def _c(fn, bound, **kw) -> HardCase:
    return HardCase(f"hard_{fn.__name__}", fn, bound, **kw)


# Bounds: the worst pipeline (forward, deferred, visbuffer, checkerboard, dacs, object_space)
# measured at 24x16 against the reference at k = 4 (python benchmarks/bench_hard_cases.py)
# times 1.5, rounded up. The 1-bit-exact cases (flat, empty) state their exact expectation.
CASES: dict[str, HardCase] = {c.name: c for c in (
    _c(degenerate, 0.15),
    _c(sliver, 0.14),
    _c(subpixel, 0.15),
    _c(near_plane, 0.09),
    _c(w_near_zero, 0.1),
    _c(far_1e5, 0.15),
    _c(far_1e7, 0.15),
    _c(far_origin, 0.15),
    _c(coplanar, 0.19),
    _c(fov_1, 0.13),
    _c(fov_170, 0.011),
    _c(grazing, 0.025),
    _c(phong_1e4, 0.14),
    _c(phong_1e6, 0.14),
    _c(bad_normals, 0.14),
    _c(zero_area_uv, 0.07),  # object_space 0.0444, tads 0.0421 (CPU, 2026-12-02)
    _c(minify, 0.02),
    _c(magnify, 1e-05),
    _c(flat, 1e-6, constant=True),
    _c(noise, 0.24),
    _c(empty, 0.0, empty=True),
    _c(tiny_image, 0.20, resolutions=((1, 16), (4096, 1))),
)}

# The scene builders by name, for the scene loader and the study (size parameters as keywords).
HARD_SCENES: dict[str, Callable[..., Scene]] = {n: c.build for n, c in CASES.items()}


def hard_case_scene(name: str, **size_params) -> Scene:
    if name not in CASES:
        raise KeyError(f"unknown hard case {name!r}; cases: {', '.join(CASES)}")
    return CASES[name].build(**size_params)


def list_hard_cases() -> list[tuple[str, str]]:
    return [(n, c.doc.splitlines()[0]) for n, c in CASES.items()]


# ------------------------------------------------------------------ metric inputs

def metric_cases(shape=(16, 16, 3)) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(test, reference) linear image pairs that stress the metrics: constant (two different
    constants), black vs black, identical noise, HDR values of 1e4 against 1e4 +- noise.
    Must hold: no NaN anywhere; PSNR may be +inf only where the images are equal."""
    rng = np.random.default_rng(5)
    a = rng.uniform(0, 1, shape)
    return {
        "constant": (np.full(shape, 0.2), np.full(shape, 0.7)),
        "black": (np.zeros(shape), np.zeros(shape)),
        "identical": (a, a.copy()),
        "hdr_1e4": (1e4 * (1 + 0.1 * a), np.full(shape, 1e4)),
        "hdr_vs_black": (np.full(shape, 1e4), np.zeros(shape)),
    }
