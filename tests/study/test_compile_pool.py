"""compile_all in worker processes (compile_pool) gives the programs of the thread path.

The process path is forced with JAXRENDER_COMPILE_PROCESSES=1 (the 2-core CI machine would
otherwise keep threads); its frames, counts and aux must equal the thread path's bitwise."""

import logging

import jax
import numpy as np
import pytest

from jaxrender.study import backend, compile_cache, compile_pool, executables, programs
from tests.study import doubles
from jaxrender.study.schema import load_study


class FakeLoader:
    """The fake scenes of ``doubles.install``, loadable in a worker (picklable by reference;
    install's own loader is a closure, which a worker cannot receive)."""

    colors = {"tiny": (1.0, 0.8, 0.6), "tiny2": (0.3, 0.9, 0.5)}

    def __call__(self, source, params):
        import jax.numpy as jnp

        return doubles.FakeScene(jnp.asarray(self.colors[source], jnp.float32), source)


def _plan(study_file):
    study = load_study(study_file)
    todo = [(s, p, v) for s in study.scenes for p in study.paths for v in study.variants]
    scenes = {s.label: backend.load_scene(s.source, dict(s.params)) for s in study.scenes}
    cams = {(s.label, p.name): backend.make_cameras(scenes[s.label],
                                                   programs.rendered_path(study, p),
                                                   *study.resolution)
            for s in study.scenes for p in study.paths}
    return study, todo, scenes, cams


def _frames(study, todo, scenes, cams, compiled):
    """Every frame of the single-frame programs and every sequence program's output."""
    out = {}
    for s, p, v in todo:
        seq_cams = cams[s.label, p.name]
        progs = programs.sequence_programs(
            study, s, v, len(seq_cams), lambda *fo: compiled[programs.program_key(s, v, *fo)])
        for t, cam in enumerate(seq_cams):
            f = progs.single.call(scenes[s.label], cam)
            out[s.label, p.name, v.label, v.params_json, t] = jax.tree.map(
                np.asarray, (f.image, f.counts, f.aux))
        for role in ("instrumented", "timed"):
            f = getattr(progs, role).call(scenes[s.label], seq_cams)
            out[s.label, p.name, v.label, v.params_json, role] = jax.tree.map(
                np.asarray, (f.image, f.counts, f.aux))
    return out


def _assert_bitwise(a, b):
    assert a.keys() == b.keys()
    for k in a:
        la, lb = jax.tree.leaves(a[k]), jax.tree.leaves(b[k])
        assert len(la) == len(lb), k
        for x, y in zip(la, lb):
            assert x.dtype == y.dtype and x.shape == y.shape, k
            assert x.tobytes() == y.tobytes(), k


def _compile(monkeypatch, mode, plan, tmp_path):
    """compile_all with threads ("0") or worker processes ("1"), each with an empty reference
    cache (so the reference programs compile too); the cached reference arrays with it."""
    from jaxrender.study import cache

    monkeypatch.setenv(compile_pool.ENV, mode)
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / f"cache{mode}"))
    out = programs.compile_all(*plan)
    study, todo, scenes, cams = plan
    refs = {}
    for s, p, _ in todo:
        for t, cam in enumerate(cams[s.label, p.name]):
            refs[s.label, p.name, t] = cache.load(cache.reference_key(
                s, cam, study.reference, study.resolution))
    return out, refs


def _keys(plan):
    """Per scene, variant and path length: the programs of ``programs.roles`` (the default
    timing: the instrumented and the images-only sequence programs, the single-frame one)."""
    study, todo, _, cams = plan
    return {programs.program_key(s, v, *fo) for s, p, v in todo
            for fo in programs.roles(study, len(cams[s.label, p.name])).values()}


def _notes(caplog):
    return [r.getMessage() for r in caplog.records if "thread instead" in r.getMessage()]


def test_switch(monkeypatch):
    monkeypatch.delenv(compile_pool.ENV, raising=False)
    assert not compile_pool.use_processes(2) and compile_pool.use_processes(3)
    monkeypatch.setenv(compile_pool.ENV, "1")
    assert compile_pool.use_processes(1)
    monkeypatch.setenv(compile_pool.ENV, "0")
    assert not compile_pool.use_processes(16)


@pytest.mark.parametrize("persistent_cache", [False, True], ids=["no-cache", "cache"])
def test_processes_match_threads(tiny_study, tmp_path, monkeypatch, caplog, persistent_cache):
    # With the persistent compilation cache on, the thread path fills it first, so a worker
    # that read it would hand back an executable loaded from it (on XLA:CPU, one that lost its
    # code on the way: the frames below would not compute).
    previous = jax.config.values["jax_compilation_cache_dir"]
    monkeypatch.setenv(compile_cache.ENV_CACHE, "1" if persistent_cache else "0")
    monkeypatch.setenv(executables.ENV_STORE, "1")
    if persistent_cache:
        compile_cache.enable(tmp_path / "xla")
    else:
        jax.config.update("jax_compilation_cache_dir", None)
    monkeypatch.setattr(backend, "load_scene", FakeLoader())
    plan = _plan(tiny_study)
    threads, ref_t = _compile(monkeypatch, "0", plan, tmp_path)
    with caplog.at_level(logging.WARNING, "jaxrender.study"):
        procs, ref_p = _compile(monkeypatch, "1", plan, tmp_path)
    assert _notes(caplog) == []  # every program (references too) came from a worker
    assert threads.keys() == procs.keys() == _keys(plan)
    assert all(c.compile_ms > 0 for c in procs.values())
    _assert_bitwise(_frames(*plan, threads), _frames(*plan, procs))
    _assert_bitwise(ref_t, ref_p)  # the references, rendered by programs from a worker
    if persistent_cache:  # the workers stored what they compiled: this process loads it all
        monkeypatch.setenv(compile_pool.ENV, "0")
        monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "cache1"))
        stored = programs.compile_all(*plan)
        assert {c.method for c in stored.values()} == {"stored"}
        _assert_bitwise(_frames(*plan, threads), _frames(*plan, stored))
    jax.config.update("jax_compilation_cache_dir", previous)


def test_unpicklable_falls_back_to_threads(tiny_study, tmp_path, monkeypatch, caplog):
    # doubles.install's scene loader is a closure: no job can go to a worker
    plan = _plan(tiny_study)
    threads, ref_t = _compile(monkeypatch, "0", plan, tmp_path)
    with caplog.at_level(logging.WARNING, "jaxrender.study"):
        procs, ref_p = _compile(monkeypatch, "1", plan, tmp_path)
    # every program and both references: none dropped, each with its note
    assert len(_notes(caplog)) == len(_keys(plan)) + 2
    assert threads.keys() == procs.keys() == _keys(plan)
    _assert_bitwise(_frames(*plan, threads), _frames(*plan, procs))
    _assert_bitwise(ref_t, ref_p)


class BadCameras:
    def __call__(self, scene, path, width, height):
        raise KeyError(f"no camera path {path.name!r} in a worker")


def test_worker_error_falls_back(tiny_study, tmp_path, monkeypatch, caplog):
    # cameras that fail in the worker: every program is compiled in a thread instead
    monkeypatch.setattr(backend, "load_scene", FakeLoader())
    plan = _plan(tiny_study)
    monkeypatch.setattr(backend, "make_cameras", BadCameras())
    with caplog.at_level(logging.WARNING, "jaxrender.study"):
        procs, _ = _compile(monkeypatch, "1", plan, tmp_path)
    notes = _notes(caplog)
    assert len(notes) == len(_keys(plan)) + 2 and all("KeyError" in n for n in notes), notes
    assert procs.keys() == _keys(plan)


REAL = """
name = "tiny_real"
resolution = "32x18"
frames = 2
save_frames = []
scenes = [{ name = "spheres", params = { rows = 1, cols = 2, lat = 6, lon = 12 } }]
paths = ["static"]

[timing]
warmup = 0
repeats = 1

[[pipelines]]
type = "object_space"
"""


@pytest.mark.slow
def test_real_object_space(tmp_path, monkeypatch):
    """A real pipeline with host-side preparation (the sheet comes back from the worker in
    the program's Prepared arguments) and the real reference, both ways."""
    f = tmp_path / "real.toml"
    f.write_text(REAL)
    plan = _plan(f)
    threads, ref_t = _compile(monkeypatch, "0", plan, tmp_path)
    procs, ref_p = _compile(monkeypatch, "1", plan, tmp_path)
    assert all(c.compile_ms > 0 for c in procs.values())
    _assert_bitwise(_frames(*plan, threads), _frames(*plan, procs))
    _assert_bitwise(ref_t, ref_p)


def test_cpu_compiles_in_the_calling_thread(tiny_study, tmp_path, monkeypatch):
    # XLA:CPU crashed when it compiled or serialized in one thread while others compiled or
    # ran programs: on the CPU backend without worker processes nothing compiles elsewhere.
    import threading

    assert jax.default_backend() == "cpu"
    monkeypatch.setattr(backend, "load_scene", FakeLoader())
    plan = _plan(tiny_study)
    seen = []
    real = programs.compile_variant

    def spy(*args, **kwargs):
        seen.append(threading.get_ident())
        return real(*args, **kwargs)

    monkeypatch.setattr(programs, "compile_variant", spy)
    out, _ = _compile(monkeypatch, "0", plan, tmp_path)
    assert out.keys() == _keys(plan)
    assert seen and set(seen) == {threading.get_ident()}, "compiled in another thread"
    assert programs.compile_workers() == 1
    monkeypatch.setenv(compile_pool.ENV, "1")
    assert not programs.compiles_in_caller()
    assert programs.compile_workers() == programs.COMPILE_WORKERS
