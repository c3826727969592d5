#!/usr/bin/env bash
# One device call (about 8 minutes): the dispatch's launch modes side by side
# (bench_launch_modes.py: foliage every pipeline at cost 0; room, and foliage at cost 256, the
# shading pipelines), the visibility pass alone for the floor, and deferred's and DACS's kernels
# under the switch. Output under $OUT.
#   device run (carry .whl): bash benchmarks/gpu_launch_modes.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=$PWD:/tmp/site PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000\|^{"; }
B="python3 benchmarks/bench_launch_modes.py --repeats 15"
timeout 280 $B --scenes foliage --json "$OUT/modes_foliage.json" 2>&1 | quiet | tee "$OUT/modes.md"
timeout 150 $B --scenes room --pipelines deferred checkerboard dacs object_space forward \
  --json "$OUT/modes_room.json" 2>&1 | quiet | tee -a "$OUT/modes.md"
timeout 120 $B --scenes foliage --costs 256 --pipelines deferred checkerboard dacs visbuffer \
  --json "$OUT/modes_cost.json" 2>&1 | quiet | tee -a "$OUT/modes.md"
timeout 40 python3 benchmarks/bench_time_work.py --scenes foliage room --pipelines visibility \
  --costs 0 --repeats 15 --out "$OUT/visibility.jsonl" 2>&1 | quiet | tee -a "$OUT/modes.md"
for p in deferred dacs; do
  JAXRENDER_DISPATCH=switch timeout 45 python3 benchmarks/profile_kernels.py $p --scene foliage \
    --top 12 --calls 3 2>&1 | quiet | tee -a "$OUT/profile.md"
done
