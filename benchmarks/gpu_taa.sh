#!/usr/bin/env bash
# TAA on the lent GPU, one device call: bench_motion.py with this tree and with the code
# before the resolve reused the pipeline's visibility (carried as .before/jaxrender), kernel
# profiles of deferred with and without TAA, then the temporal_stability study (resumable:
# a run cut by the time limit keeps its rows). Output under $OUT.
#   device run (carry .whl and .before): bash benchmarks/gpu_taa.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
SITE=${SITE:-/tmp/site}
export PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
now=$PWD:$SITE; before=$PWD/.before:$SITE
for v in now before; do
  PYTHONPATH=${!v} timeout 100 python3 benchmarks/bench_motion.py --frames 8 --repeats 20 \
    --json "$OUT/motion_$v.json" 2>&1 | quiet | sed "s/^/[$v] /" | tee -a "$OUT/motion.md"
done
for s in "" "--set taa=true"; do
  PYTHONPATH=$now timeout 60 python3 benchmarks/profile_kernels.py deferred --scene spheres_spin \
    $s --top 0 --calls 10 2>&1 | quiet | grep wall | tee -a "$OUT/motion.md"
done
PYTHONPATH=$now timeout ${STUDY_S:-330} python3 -m jaxrender study temporal_stability \
  --out "$OUT/ts" --no-progress 2>&1 | quiet | tail -40
tar -czf "$OUT/temporal_stability.tgz" -C "$OUT" ts && rm -rf "$OUT/ts"
