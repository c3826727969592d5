"""The reference frames a study scores against: rendered once per camera and kept in the
reference cache (``cache``), so that every pipeline of every run compares with the same image.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrender import timing
from jaxrender.study import backend, cache, executables, store


def compile_reference(scene, cam, ref, resolution) -> timing.Compiled:
    """The reference's single-frame program: references are rendered and cached per frame."""
    pipe = backend.pipeline(ref.pipeline)
    cfg = backend.make_config(ref.pipeline, *resolution, dict(ref.params))
    return executables.compile_program(pipe, scene, cam, cfg)


def _keys(spec, cams, ref, resolution, first_frame: int, moving: bool) -> list[str]:
    """A moving scene's reference differs per frame of the clock, not only per camera."""
    return [cache.reference_key(spec, c, ref, resolution,
                                first_frame + i if moving else None) for i, c in enumerate(cams)]


def all_cached(spec, cams, ref, resolution, *, first_frame: int = 0, moving: bool = False
               ) -> bool:
    return all(cache.has(k) for k in _keys(spec, cams, ref, resolution, first_frame, moving))


def reference_frames(scene, spec, cams, ref, resolution, programs: dict | None = None, *,
                     first_frame: int = 0) -> list[dict]:
    """The reference frame of each camera, from the cache or rendered and cached; camera i is
    frame ``first_frame + i`` of the animation clock (the scene posed there). ``programs``
    (scene label -> compiled reference, or a Future of one) lets a scene's camera paths share
    one compile."""
    programs = {} if programs is None else programs
    out, compiled = [], programs.get(spec.label)
    if hasattr(compiled, "result"):  # still compiling in the runner's pool
        compiled = programs[spec.label] = compiled.result()
    moving = getattr(scene, "animation", None) is not None
    keys = _keys(spec, cams, ref, resolution, first_frame, moving)
    for i, (cam, key) in enumerate(zip(cams, keys)):
        arrays = cache.load(key)
        if arrays is None:
            if compiled is None:
                compiled = programs[spec.label] = compile_reference(scene, cam, ref,
                                                                    resolution)
            frame = compiled.call(scene, cam, t=first_frame + i)
            arrays = {"image": np.asarray(frame.image, np.float32)}
            conv = frame.counts.get("convergence_psnr") if frame.counts else None
            if conv is not None:
                arrays["convergence_psnr"] = np.float64(store.json_number(conv))
            cache.save(key, arrays)
        out.append(arrays)
    return out


def rebuild(study, *, log=print) -> int:
    """Re-render every reference frame a study needs; returns the number of frames."""
    n = 0
    for spec in study.scenes:
        scene = backend.load_scene(spec.source, dict(spec.params))
        warm = study.warmup_frames
        for path in study.paths:
            # The frames the runner scores: the path rendered with its warm-up, which is dropped.
            rendered = dataclasses.replace(path, frames=path.frames + warm)
            cams = backend.make_cameras(scene, rendered, *study.resolution)[warm:]
            for key in _keys(spec, cams, study.reference, study.resolution, warm,
                             getattr(scene, "animation", None) is not None):
                cache.remove(key)
            reference_frames(scene, spec, cams, study.reference, study.resolution,
                             first_frame=warm)
            n += len(cams)
            log(f"rebuilt {len(cams)} reference frame(s): {spec.label} / {path.name}")
    return n
