python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl && export PYTHONPATH=$PWD:/tmp/site || exit
export XLA_PYTHON_CLIENT_MEM_FRACTION=0.3 PYTHONUNBUFFERED=1
python3 -c "import jax; print(jax.__version__, jax.devices())"
timeout 280 python3 benchmarks/bench_compile_cache.py --study studies/quickstart.toml 2>&1 | tee $OUT/cc_quickstart.txt
timeout 290 python3 benchmarks/bench_compile_cache.py --study studies/temporal_stability.toml --frames 2 2>&1 | tee $OUT/cc_temporal.txt
