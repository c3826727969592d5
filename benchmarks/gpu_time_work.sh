#!/usr/bin/env bash
# Time against work on the lent GPU (one device call, under 7 minutes): kernel profiles of
# forward and DACS, then bench_time_work.py on foliage and room. Output under $OUT.
#   device run: bash benchmarks/gpu_time_work.sh
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
for p in forward dacs; do
  timeout 60 python3 benchmarks/profile_kernels.py $p --scene foliage --top 10 --calls 3 2>&1 \
    | quiet | tee -a "$OUT/profile.md"
done
timeout ${TIME_WORK_S:-300} python3 benchmarks/bench_time_work.py --scenes foliage room \
  --costs 0 16 64 --repeats 7 --budget $(( ${TIME_WORK_S:-300} - 30 )) \
  --out "$OUT/time_work.jsonl" --label after 2>&1 | quiet | grep -v '^{'
