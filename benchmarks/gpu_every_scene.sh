#!/usr/bin/env bash
# Every pipeline's per-frame time inside a 16-frame sequence (how studies time a frame) on every
# built-in scene at 1920x1080 with its default shader, and the visibility pass alone on each
# scene for the floor. Rows stream to $OUT as JSON lines. Three parts, one device call each
# (about 5 minutes apiece; glass alone compiles for 25-30 s a pipeline), back to back so the
# machine stays warm:
#   device run (carry .whl): bash benchmarks/gpu_every_scene.sh 1   (then 2, then 3)
# With no part, all three in one call (over 10 minutes: it cannot finish within one call).
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=$PWD:/tmp/site PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
ALL="stripes spheres foliage thin terrain sliver room many_small foliage_wind spheres_spin grass glass"
S="python3 benchmarks/bench_sequence.py --frames 16 --rounds 5 --no-single"
for part in ${@:-1 2 3}; do
  if [ "$part" = 1 ]; then
    timeout 60 python3 benchmarks/bench_time_work.py --scenes $ALL --pipelines visibility \
      --costs 0 --repeats 15 --out "$OUT/visibility.jsonl" 2>&1 | quiet | tail -20 \
      | tee "$OUT/every_scene.md"
    timeout 250 $S --scenes stripes spheres foliage thin terrain sliver 2>&1 | quiet \
      | tee -a "$OUT/every_scene.md"
  elif [ "$part" = 2 ]; then
    timeout 280 $S --scenes room many_small foliage_wind spheres_spin 2>&1 | quiet \
      | tee -a "$OUT/every_scene.md"
  elif [ "$part" = 3 ]; then
    timeout 280 $S --scenes grass glass 2>&1 | quiet | tee -a "$OUT/every_scene.md"
  fi
done
