#!/usr/bin/env bash
# Time against work, and the motion benchmark, on the lent GPU (one device call, about 6.5
# minutes): kernel profiles of forward and DACS on foliage, bench_time_work.py (foliage at
# shader costs 0, 16, 64; room at cost 0), bench_motion.py. Output under $OUT.
#   device run: bash benchmarks/gpu_time_work.sh
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
for p in forward dacs; do
  timeout 45 python3 benchmarks/profile_kernels.py $p --scene foliage --top 10 --calls 3 2>&1 \
    | quiet | tee -a "$OUT/profile.md"
done
TW="python3 benchmarks/bench_time_work.py --repeats 7 --out $OUT/time_work.jsonl --label after"
timeout 200 $TW --scenes foliage --costs 0 16 64 --budget 185 2>&1 | quiet | grep -v '^{'
timeout 70 $TW --scenes room --costs 0 --budget 60 2>&1 | quiet | grep -v '^{'
timeout 100 python3 benchmarks/bench_motion.py --json "$OUT/motion.json" 2>&1 | quiet \
  | tee "$OUT/motion.md"
