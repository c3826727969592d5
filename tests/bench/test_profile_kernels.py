"""The kernel profiler's scope sums: an instruction counts under every named scope on its
path, however deep the path (a path cut to its last characters once dropped the outer
scopes, and deferred's lighting read half its kernels' time)."""

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks.profile_kernels import hlo_sources, pipeline_program, short_source


def nested(x):
    with jax.named_scope("outer_scope"):
        for depth in range(8):
            with jax.named_scope(f"inner_scope_number_{depth}"):
                x = jnp.sin(x) * 3.0 + jnp.cos(x)
    return jnp.sum(x)


def test_scope_matches_anywhere_on_a_long_path(rng):
    x = jnp.asarray(rng.normal(size=(64,)).astype(np.float32))
    sources = hlo_sources(jax.jit(nested).lower(x).compile().as_text())
    deep = [s for s in sources.values() if "inner_scope_number_7/" in s]
    assert deep, f"no instruction from the innermost scope among {list(sources.values())[:8]}"
    missing = [s for s in deep if "outer_scope/" not in s]
    assert not missing, f"outer scope lost from {missing[:3]}"
    shown = short_source(deep[0], keep=30)
    assert len(shown.partition(" @ ")[0]) == 30, shown
    assert shown.partition(" @ ")[2] == deep[0].partition(" @ ")[2], (shown, deep[0])


def test_a_prepared_pipeline_is_profiled_as_compiled_for_a_sequence():
    # Object space builds its sheet on the host: the profiler compiles the program as the
    # benchmarks do, so a sequence of it runs (it once failed, traced inside another jit).
    from jaxrender.pipelines import get_pipeline, make_config
    from jaxrender.scene.camera_path import stack
    from jaxrender.shading import load_lit_scene

    scene = load_lit_scene("spheres")
    pipe, cfg = get_pipeline("object_space"), make_config("object_space", width=32, height=18)
    cameras = stack([scene.camera] * 2)
    run, text = pipeline_program(pipe, scene, cameras, cfg, sequence=True)
    want = pipe.render_sequence(scene, cameras, cfg).image
    np.testing.assert_array_equal(np.asarray(run()), np.asarray(want),
                                  err_msg="the profiled program renders another image")
    assert "shade/" in " ".join(hlo_sources(text).values()), "no scope in the program's text"
