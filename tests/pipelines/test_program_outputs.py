"""A timed program returns the images alone (``program.OUTPUTS``): it renders the same images
as the instrumented program, bit for bit, and XLA drops the work that only the counts and
views need, so its compiled program reads and writes fewer bytes."""

from __future__ import annotations

import numpy as np
import pytest

from jaxrender import camera_path
from jaxrender.pipelines import make_config, program
from jaxrender.pipelines.registry import get_pipeline
from jaxrender.shading import load_lit_scene

W, H, FRAMES = 48, 27, 2


def _bytes_accessed(compiled) -> float:
    cost = compiled.cost_analysis()
    cost = cost[0] if isinstance(cost, (list, tuple)) else cost
    return float(cost["bytes accessed"])


def test_images_only_renders_the_same_images_and_drops_the_counts_work():
    # TADS: a stateful pipeline (its shade texture carries over) whose counts are the
    # heaviest, a pass over every texel of its sheet (RESULTS, twenty-third session).
    name = "tads"
    scene = load_lit_scene("spheres")
    path = camera_path.pan(scene.camera, FRAMES, pixels_per_frame=1.0, height=H)
    pipe, cfg = get_pipeline(name), make_config(name, width=W, height=H)
    out, accessed = {}, {}
    for outputs in program.OUTPUTS:
        lowered, prepared = program.lower(pipe, scene, path, cfg, sequence=True,
                                          outputs=outputs)
        compiled = lowered.compile()
        accessed[outputs] = _bytes_accessed(compiled)
        out[outputs] = program.bind(pipe, cfg, compiled, prepared)(scene, path)
    every, images = out["all"], out["images"]
    assert set(images.counts) == {"overflow"} and not images.aux, (
        f"{name}: the images-only frames hold {sorted(images.counts)} and {sorted(images.aux)}")
    assert len(every.counts) > 1 and every.aux, f"{name}: the instrumented frames lost counts"
    np.testing.assert_array_equal(np.asarray(images.image), np.asarray(every.image),
                                  err_msg=f"{name}: the images-only program renders otherwise")
    np.testing.assert_array_equal(np.asarray(images.counts["overflow"]),
                                  np.asarray(every.counts["overflow"]), err_msg=name)
    # More than the counts and views themselves: computation was dropped, not only writes.
    written = sum(np.asarray(v).nbytes for d in (every.counts, every.aux) for v in d.values())
    assert accessed["all"] - accessed["images"] > written, (
        f"{name}: the images-only program accesses {accessed['images']:.4g} bytes, the "
        f"instrumented one {accessed['all']:.4g}, which writes {written} bytes of counts and "
        f"views: XLA kept the counts' work")


def test_unknown_outputs_are_refused():
    scene = load_lit_scene("spheres")
    with pytest.raises(ValueError, match="outputs must be one of all, images"):
        program.lower(get_pipeline("deferred"), scene, scene.camera,
                      make_config("deferred", width=W, height=H), outputs="counts")
