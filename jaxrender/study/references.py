"""The reference frames a study scores against: rendered once per camera and kept in the
reference cache (``cache``), so that every pipeline of every run compares with the same image.
"""

from __future__ import annotations

import numpy as np

from jaxrender import timing
from jaxrender.study import backend, cache, executables, store


def compile_reference(scene, cam, ref, resolution) -> timing.Compiled:
    """The reference's single-frame program: references are rendered and cached per frame."""
    pipe = backend.pipeline(ref.pipeline)
    cfg = backend.make_config(ref.pipeline, *resolution, dict(ref.params))
    return executables.compile_program(pipe, scene, cam, cfg)


def all_cached(spec, cams, ref, resolution) -> bool:
    return all(cache.has(cache.reference_key(spec, c, ref, resolution)) for c in cams)


def reference_frames(scene, spec, cams, ref, resolution, programs: dict | None = None
                     ) -> list[dict]:
    """The reference frame of each camera, from the cache or rendered and cached. ``programs``
    (scene label -> compiled reference, or a Future of one) lets a scene's camera paths share
    one compile."""
    programs = {} if programs is None else programs
    out, compiled = [], programs.get(spec.label)
    if hasattr(compiled, "result"):  # still compiling in the runner's pool
        compiled = programs[spec.label] = compiled.result()
    for cam in cams:
        key = cache.reference_key(spec, cam, ref, resolution)
        arrays = cache.load(key)
        if arrays is None:
            if compiled is None:
                compiled = programs[spec.label] = compile_reference(scene, cam, ref,
                                                                    resolution)
            frame = compiled.call(scene, cam)
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
        for path in study.paths:
            cams = backend.make_cameras(scene, path, *study.resolution)
            for cam in cams:
                cache.remove(cache.reference_key(spec, cam, study.reference, study.resolution))
            reference_frames(scene, spec, cams, study.reference, study.resolution)
            n += len(cams)
            log(f"rebuilt {len(cams)} reference frame(s): {spec.label} / {path.name}")
    return n
