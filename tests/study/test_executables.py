"""The executable store: a rerun loads every program it compiled before without lowering one,
with results equal to compiled ones; a changed static config or shape misses; a damaged entry
compiles again; ``JAXRENDER_COMPILATION_CACHE=0`` turns it off; an executable JAX's own cache
loaded is never stored."""

import json
import logging
import re
import threading
import time

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.experimental.compilation_cache import compilation_cache as jax_cache

from jaxrender.pipelines import dispatch, program, registry
from jaxrender.scene.camera import look_at
from jaxrender.study import compile_cache, executables
from jaxrender.study.runner import run_study
from jaxrender.study.schema import load_study
from jaxrender.types import Frame
from tests.study import doubles

@pytest.fixture(autouse=True)
def store_on(monkeypatch):
    """The store is off by default on the CPU backend: these tests turn it on."""
    monkeypatch.setenv(executables.ENV_STORE, "1")


def _what(rows):
    """The rows without the columns that say how fast and how the program was obtained."""
    neutral = lambda k: k.endswith("_ms") or k.startswith(("time_", "compile_"))  # noqa: E731
    # As JSON, so that a NaN equals a NaN and every float is compared to its last bit.
    return json.dumps([{k: v for k, v in r.items() if not neutral(k)} for r in rows],
                      sort_keys=True)


def _study(tiny_study, out, monkeypatch):
    lines = []
    monkeypatch.setenv("JAXRENDER_CACHE", str(out.parent / "cache"))
    res = run_study(load_study(tiny_study), out, progress=False, log=lines.append)
    # One line per batch of programs (``program_batches``)
    return res, "\n".join(ln for ln in lines if "program(s)" in ln)


def _store_counts(lines):
    """(loaded, compiled) summed over the batches' lines; None where no line names them."""
    found = re.findall(r"executable store: (\d+) loaded, (\d+) compiled", lines)
    return tuple(sum(int(m[i]) for m in found) for i in (0, 1)) if found else None


def test_rerun_loads_every_program(tiny_study, tmp_path, monkeypatch):
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    # As in a new process: programs jax kept in memory from the tests before are not stored.
    jax.clear_caches()
    first, line1 = _study(tiny_study, tmp_path / "one", monkeypatch)
    n = sum(int(m) for m in re.findall(r"(\d+) program\(s\)", line1))
    assert _store_counts(line1) == (0, n + 2), line1  # and both scenes' reference programs
    assert "not stored" not in line1, line1
    stored = list(executables.folder().glob(f"*{executables.SUFFIX}"))
    assert len(stored) == n + 2, stored
    second, line2 = _study(tiny_study, tmp_path / "two", monkeypatch)
    assert _store_counts(line2) == (n, 0), line2
    assert {r["compile_method"] for r in second.rows} == {"stored"}
    assert _what(second.rows) == _what(first.rows), "programs from the store computed otherwise"
    monkeypatch.setenv(compile_cache.ENV_CACHE, "0")
    third, line3 = _study(tiny_study, tmp_path / "three", monkeypatch)
    assert _store_counts(line3) is None, line3
    assert {r["compile_method"] for r in third.rows} == {"aot"}
    assert _what(third.rows) == _what(first.rows), "the store changed a result"


# ------------------------------------------------------------------ keys and entries


def _frame(scene, camera, cfg):
    img = jnp.broadcast_to(scene * camera.eye[0] + cfg.width, (cfg.height, cfg.width, 3))
    return Frame(img, {"overflow": jnp.int32(0)}, {})


PIPE = registry.Pipeline("affine", registry.RenderConfig, registry.FrameStep(_frame))


def _key(cfg, frames, step=0.1):
    cams = [look_at((step * t, 0.5, 3.0), (0.0, 0.0, 0.0)) for t in range(frames)]
    fixed, args, _ = program.arguments(PIPE, jnp.ones(3), cams, cfg, sequence=True)
    return executables.program_key(PIPE, fixed, args)


def test_key_follows_static_config_and_shapes_not_values(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    cfg = registry.RenderConfig(width=4, height=2)
    key = _key(cfg, 3)
    assert key is not None and key == _key(cfg, 3)
    assert _key(cfg, 3, step=0.3) == key, "a camera move is an argument, not a new program"
    assert _key(registry.RenderConfig(width=5, height=2), 3) != key, "static config"
    assert _key(cfg, 4) != key, "path length (argument shape)"
    fixed, args, _ = program.arguments(PIPE, jnp.ones(3, jnp.int32), look_at(
        (0, 0.5, 3), (0, 0, 0)), cfg)
    one = executables.program_key(PIPE, fixed, args)
    fixed, args, _ = program.arguments(PIPE, jnp.ones(3), look_at((0, 0.5, 3), (0, 0, 0)), cfg)
    assert len({one, executables.program_key(PIPE, fixed, args), key}) == 3, "dtype, mode"


def test_key_follows_a_named_launch_mode(tmp_path, monkeypatch):
    # Naming the default mode still changes deferred's program (its screen passes go back to
    # the chunked dispatch), so a stored default program must not be loaded for it.
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    cfg = registry.RenderConfig(width=4, height=2)
    keys = {}
    for named in ("", dispatch.DEFAULT_LAUNCH, "loop"):
        monkeypatch.setenv(dispatch.ENV_LAUNCH, named)
        keys[named] = _key(cfg, 3)
    assert len(set(keys.values())) == 3, keys


def _compile(cfg):
    cam = look_at((0.2, 0.5, 3.0), (0.0, 0.0, 0.0))
    before = executables.counts()
    comp = executables.compile_program(PIPE, jnp.ones(3), cam, cfg)
    after = executables.counts()
    image = np.asarray(comp.call(jnp.ones(3), cam).image)
    return comp, {k: after[k] - before[k] for k in after}, image


def _expected(cfg):
    return np.full((cfg.height, cfg.width, 3), 0.2 + cfg.width, np.float32)


@pytest.fixture
def store(tmp_path, monkeypatch):
    """An empty store, used as compile_all uses it: JAX's cache (which a test before may have
    turned on) suspended, so that XLA compiles what the store misses."""
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    with compile_cache.suspended():
        yield executables.folder()


def test_a_changed_config_misses(store):
    for width, loaded in ((4, 0), (4, 1), (6, 0)):
        cfg = registry.RenderConfig(width=width, height=4)
        comp, n, image = _compile(cfg)
        assert (n["loaded"], n["compiled"]) == (loaded, 1 - loaded), (width, n)
        np.testing.assert_array_equal(image, _expected(cfg), err_msg=f"width {width}")


@pytest.mark.parametrize("damage", ["truncated", "flipped", "foreign"])
def test_a_damaged_entry_compiles_again(store, caplog, damage):
    # A program of its own: one this process compiled before would not be stored (in memory).
    cfg = registry.RenderConfig(width={"truncated": 9, "flipped": 10, "foreign": 11}[damage],
                                height=5)
    _compile(cfg)
    (entry,) = store.glob(f"*{executables.SUFFIX}")
    blob = entry.read_bytes()
    if damage == "truncated":
        entry.write_bytes(blob[: len(blob) // 2])
    elif damage == "flipped":
        entry.write_bytes(blob[:-8] + bytes(b ^ 0xFF for b in blob[-8:]))
    else:  # a well-formed entry whose payload is no executable
        assert executables.write(entry.stem, b"not an executable")
    jax.clear_caches()  # as a new process would: compiled by XLA, so stored again
    with caplog.at_level(logging.WARNING, "jaxrender.study"):
        comp, n, image = _compile(cfg)
    assert (n["loaded"], n["compiled"]) == (0, 1), n
    assert any("executable store" in r.getMessage() for r in caplog.records), caplog.text
    np.testing.assert_array_equal(image, _expected(cfg), err_msg=damage)
    comp, n, image = _compile(cfg)  # stored again, whole
    assert (n["loaded"], n["compiled"]) == (1, 0) and comp.method == "stored", n
    np.testing.assert_array_equal(image, _expected(cfg), err_msg=f"{damage}, reloaded")


def test_off_with_the_compilation_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.setenv(compile_cache.ENV_CACHE, "0")
    cfg = registry.RenderConfig(width=4, height=2)
    assert _key(cfg, 3) is None
    for _ in range(2):
        comp, n, image = _compile(cfg)
        assert comp.method == "aot" and n == {"loaded": 0, "compiled": 0, "unstored": 0}, n
    assert not executables.folder().exists()
    np.testing.assert_array_equal(image, _expected(cfg), err_msg="store off")


def test_stores_only_what_xla_compiled_just_now(tmp_path, monkeypatch):
    # On XLA:CPU an executable loaded from JAX's cache serializes without its code; one jax
    # kept in memory may be such an executable. Either is used, never stored.
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.setenv(compile_cache.ENV_CACHE, "1")  # JAX's cache, off by default on the CPU
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    previous = jax.config.values["jax_compilation_cache_dir"]
    cfg = registry.RenderConfig(width=7, height=3)
    entries = lambda: list(executables.folder().glob(f"*{executables.SUFFIX}"))  # noqa: E731
    try:
        compile_cache.enable()
        jax.clear_caches()
        for step, clear, unstored in (("compiled", False, 0), ("in memory", False, 1),
                                      ("from JAX's cache", True, 1)):
            for entry in entries():
                entry.unlink()
            if clear:
                jax.clear_caches()  # the next compile asks JAX's cache on disk
            comp, n, image = _compile(cfg)
            assert n == {"loaded": 0, "compiled": 1, "unstored": unstored}, (step, n)
            assert len(entries()) == 1 - unstored, step
            np.testing.assert_array_equal(image, _expected(cfg), err_msg=step)
        jax.clear_caches()
        with compile_cache.suspended():  # as compile_all does: XLA compiles, the store keeps it
            comp, n, image = _compile(cfg)
        assert n == {"loaded": 0, "compiled": 1, "unstored": 0} and len(entries()) == 1, n
        comp, n, image = _compile(cfg)
        assert n["loaded"] == 1, n
        np.testing.assert_array_equal(image, _expected(cfg), err_msg="stored, loaded")
    finally:
        jax.config.update("jax_compilation_cache_dir", previous)
        jax_cache.reset_cache()


def test_a_pipeline_is_keyed_by_the_file_defining_it():
    # The same name, config and arguments, a function from another file: another program (a
    # pipeline registered from outside the package is not in the code version).
    cfg = registry.RenderConfig(width=4, height=2)
    elsewhere = registry.Pipeline("affine", registry.RenderConfig,
                                  registry.FrameStep(doubles.render_flat))
    fixed, args, _ = program.arguments(PIPE, jnp.ones(3), [look_at((0, 0.5, 3), (0, 0, 0))],
                                       cfg, sequence=True)
    assert executables.program_key(PIPE, fixed, args) != executables.program_key(
        elsewhere, (elsewhere,) + fixed[1:], args)


def test_deferred_stores_write_when_the_block_ends(store):
    cfg = registry.RenderConfig(width=12, height=3)
    with executables.deferred_stores():
        comp, n, image = _compile(cfg)
        assert n["compiled"] == 1 and not list(store.glob(f"*{executables.SUFFIX}")), \
            "stored inside the block, beside compiles in other threads"
    assert len(list(store.glob(f"*{executables.SUFFIX}"))) == 1, "not stored at the block's end"
    jax.clear_caches()
    comp, n, image = _compile(cfg)
    assert n["loaded"] == 1 and comp.method == "stored", n
    np.testing.assert_array_equal(image, _expected(cfg), err_msg="deferred, then loaded")


def test_an_exclusive_hold_waits_for_shared_ones_and_goes_first():
    guard, order = executables.SharedExclusive(), []

    def exclusive():
        with guard.exclusive():
            order.append("exclusive")

    def late_shared():
        with guard.shared():
            order.append("late shared")

    with guard.shared():
        writer = threading.Thread(target=exclusive)
        writer.start()
        while guard.waiting() == 0:  # the exclusive hold is queued behind this shared one
            time.sleep(0.001)
        reader = threading.Thread(target=late_shared)
        reader.start()
        time.sleep(0.05)
        assert order == [], f"entered beside a shared hold: {order}"
        order.append("first shared released")
    writer.join(5)
    reader.join(5)
    assert order == ["first shared released", "exclusive", "late shared"], order


@pytest.mark.parametrize("value, on", [(None, False), ("1", True), ("0", False), ("off", False)])
def test_off_by_default_on_the_cpu_backend(monkeypatch, value, on):
    assert jax.default_backend() == "cpu"
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    if value is None:
        monkeypatch.delenv(executables.ENV_STORE, raising=False)
    else:
        monkeypatch.setenv(executables.ENV_STORE, value)
    assert executables.enabled() is on, f"{executables.ENV_STORE}={value}"
