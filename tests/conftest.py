"""Strict numerics for every test (as Equinox does): implicit rank or dtype promotion is a bug."""

import os
import subprocess
import sys
import warnings
import zlib

os.environ.setdefault("JAX_PLATFORMS", "cpu")
# Tests compile in threads (the fake scenes cannot be sent to worker processes); the process
# path has its own tests, which force it (tests/study/test_compile_pool.py).
os.environ.setdefault("JAXRENDER_COMPILE_PROCESSES", "0")
# The tests run tiny inputs through many distinct programs, so XLA compile time dominates the
# suite. LLVM at -O0 halves compile time and doubles run time, a good trade here. XLA:CPU's
# older loop emitters (``xla_cpu_use_fusion_emitters=false``) compile these programs in about
# 60% of the time its MLIR fusion emitters take (benchmarks/RESULTS.md, "The test suite's
# compiles"). With them alone, two programs that must agree bit for bit (one launch against
# chunks, spans against bounding boxes) differed by rounding (up to about 4e-6); capped at
# AVX, which has no fused multiply-add, they agree again (so, likely, some loops fused a
# multiply-add and others did not). What that gives up: the suite checks such equalities in a
# compile without fused multiply-adds, not in the fusion emitters' compile it used before.
# Never used for timings: benchmarks and studies run at XLA's defaults. A flag the caller set
# wins.
TEST_XLA_FLAGS = {"xla_backend_optimization_level": "0", "xla_cpu_use_fusion_emitters": "false",
                  "xla_cpu_max_isa": "AVX"}


def with_test_flags(flags: str) -> str:
    """``flags`` plus each of TEST_XLA_FLAGS it does not name, if this jaxlib knows them (XLA
    aborts on a flag it does not know; the xdist workers inherit the checked flags)."""
    added = " ".join(f"--{n}={v}" for n, v in TEST_XLA_FLAGS.items() if n not in flags)
    if not added:
        return flags
    env = dict(os.environ, XLA_FLAGS=f"{flags} {added}".strip(), JAX_PLATFORMS="cpu")
    probe = subprocess.run([sys.executable, "-c", "import jax; jax.devices()"], env=env,
                           capture_output=True, text=True)
    if probe.returncode == 0:
        return env["XLA_FLAGS"]
    warnings.warn(f"this jaxlib refuses the test suite's XLA flags ({added}); the tests compile "
                  f"without them, slower:\n{probe.stderr[-500:]}")
    return flags


os.environ["XLA_FLAGS"] = with_test_flags(os.environ.get("XLA_FLAGS", ""))

import jax  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from jaxrender import memory_maps  # noqa: E402

jax.config.update("jax_numpy_rank_promotion", "raise")
jax.config.update("jax_numpy_dtype_promotion", "strict")


@pytest.fixture
def rng(request):
    # A fresh stream per test, reproducible: seeded by the test's name, plus JAXRENDER_SEED to
    # draw other inputs on purpose (CI runs the default).
    extra = int(os.environ.get("JAXRENDER_SEED", "0"))
    return np.random.default_rng(zlib.crc32(request.node.name.encode()) + extra)


@pytest.fixture(autouse=True)
def _jax_cache_setting_restored():
    # A test that turns JAX's persistent cache on (jax.config is process-wide) leaves it off for
    # the tests after it in the same worker: XLA:CPU aborted in this cache's write during a
    # later test twice.
    from jax.experimental.compilation_cache import compilation_cache

    names = ("jax_compilation_cache_dir", "jax_enable_compilation_cache")
    before = {n: jax.config.values[n] for n in names}
    yield
    changed = {n: v for n, v in before.items() if jax.config.values[n] != v}
    for name, value in changed.items():
        jax.config.update(name, value)
    if changed:
        compilation_cache.reset_cache()


@pytest.fixture(autouse=True)
def _compiled_programs_released():
    # A worker keeps the compiled programs of every test it ran in jax's caches, and XLA:CPU
    # maps memory for each of their kernels: past the kernel's vm.max_map_count the next
    # compile segfaults (the CI crashes in test_exact and test_robust). Past half the limit,
    # the programs no test holds are dropped (jaxrender.memory_maps).
    yield
    memory_maps.release_if_crowded()


# The files that take longest on a 2-core machine (per-file sums of the tests' times from
# pytest's junit report, 2026-12-07, this file's XLA flags, a dev venv: 1,243 s of test time
# in a 638 s run), handed to the xdist workers first: with --dist loadfile a file runs whole
# on one worker, and a long file dispatched last leaves the other worker idle at the end of
# the run. Files under about 18 s go out in collection order.
LONGEST_FIRST = (
    "tests/pipelines/test_transparency.py",  # 117 s
    "tests/test_installed.py",  # 113: the README example in a fresh interpreter, a wheel
    "tests/pipelines/test_reference.py",  # 88
    "tests/study/test_runner.py",  # 46
    "tests/raster/test_spans.py",  # 45
    "tests/raster/test_multi_sample.py",  # 43
    "tests/study/test_time_study.py",  # 41
    "tests/pipelines/test_forward.py",  # 40
    "tests/pipelines/test_taa.py",  # 37
    "tests/study/test_sequences.py",  # 34
    "tests/pipelines/test_visbuffer.py",  # 32
    "tests/pipelines/test_waves_and_worklists.py",  # 32
    "tests/pipelines/test_transparent_prefix.py",  # 30
    "tests/pipelines/test_dacs.py",  # 29
    "tests/pipelines/test_object_space.py",  # 28
    "tests/raster/test_donate.py",  # 26
    "tests/pipelines/test_tads.py",  # 26
    "tests/raster/test_robust.py",  # 21
    "tests/study/test_devices.py",  # 20
    "tests/pipelines/test_checkerboard.py",  # 20
    "tests/shading/test_render.py",  # 20
    "tests/pipelines/test_os_budget.py",  # 19
    "tests/pipelines/test_deferred.py",  # 19
    "tests/pipelines/test_vertex_work.py",  # 18
)


def pytest_collection_modifyitems(config, items):
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    root = config.rootpath

    def key(item):
        return rank.get(item.path.relative_to(root).as_posix(), len(rank))

    items.sort(key=key)  # stable: every other file keeps its collection order
