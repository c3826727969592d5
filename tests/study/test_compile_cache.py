"""The persistent compilation cache: under jaxrender's cache folder, a user's own JAX setting
left alone, off on request (and by default on the CPU), and a program compiled once loaded the
next time."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.study import compile_cache


def _program(c: float):
    # A constant of its own makes the program new to every cache.
    # Lowered from a shape alone: no eager work whose own compiles would blur the counts.
    return jax.jit(lambda x: jnp.sin(x) * c + c).lower(jax.ShapeDtypeStruct((7,), jnp.float32))


def test_compiled_once_then_loaded(tmp_path, monkeypatch, rng):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.setenv(compile_cache.ENV_CACHE, "1")  # off by default on the CPU
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    folder = compile_cache.enable()
    assert folder == tmp_path / "xla", folder
    c = float(rng.uniform(1.0, 2.0))
    lowered = _program(c)
    before = compile_cache.counts()
    first = lowered.compile()
    after_first = compile_cache.counts()
    jax.clear_caches()  # drop the in-memory executables: the next compile asks the disk
    second = _program(c).compile()
    after_second = compile_cache.counts()
    assert after_first["misses"] - before["misses"] == 1, (before, after_first)
    assert after_second["misses"] == after_first["misses"], (after_first, after_second)
    assert after_second["hits"] - after_first["hits"] == 1, (after_first, after_second)
    assert any(p.name.endswith("-cache") for p in folder.iterdir()), list(folder.iterdir())
    x = jnp.arange(7, dtype=jnp.float32)
    np.testing.assert_array_equal(np.asarray(first(x)), np.asarray(second(x)),
                                  err_msg="the cached executable computes something else")


def test_follows_jaxrender_cache_and_can_be_turned_off(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "one"))
    monkeypatch.setenv(compile_cache.ENV_CACHE, "1")  # off by default on the CPU
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    assert compile_cache.enable() == tmp_path / "one" / "xla"
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "two"))
    assert compile_cache.enable() == tmp_path / "two" / "xla"
    assert jax.config.values["jax_compilation_cache_dir"] == str(tmp_path / "two" / "xla")
    monkeypatch.setenv(compile_cache.ENV_CACHE, "0")
    assert compile_cache.enable() is None


def test_a_users_own_cache_folder_wins(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path / "ours"))
    monkeypatch.setenv(compile_cache.ENV_CACHE, "1")  # off by default on the CPU
    monkeypatch.setenv("JAX_COMPILATION_CACHE_DIR", str(tmp_path / "theirs"))
    assert compile_cache.enable() == tmp_path / "theirs"
    assert jax.config.values["jax_compilation_cache_dir"] == str(tmp_path / "theirs")


def test_off_by_default_on_the_cpu_backend(tmp_path, monkeypatch):
    assert jax.default_backend() == "cpu"
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    monkeypatch.delenv(compile_cache.ENV_CACHE, raising=False)
    previous = jax.config.values["jax_compilation_cache_dir"]
    assert compile_cache.enable() is None
    assert jax.config.values["jax_compilation_cache_dir"] == previous, "the setting changed"
    assert not (tmp_path / "xla").exists()
