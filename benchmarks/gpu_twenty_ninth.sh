#!/usr/bin/env bash
# Prepared in the twenty-ninth session (carry [".whl", ".v"]; .v/base and .v/ckmat as
# gpu_twenty_eighth.sh's header builds them):
#   bash benchmarks/gpu_twenty_ninth.sh dacsprof grouped ckmat
# dacsprof: DACS and deferred on foliage at shader costs 0 and 256, kernels by scope
#   (profile_kernels.py --shader-cost), and DACS's optimized programs at cost 256. DACS's
#   slope was 1.6-2.0x deferred's (twenty-eighth session) with about the same lanes launched
#   per point shaded; per lane and layer 11.6 ps against 6.1. Which kernels grow with the cost
#   in each, and by how much per lane launched? Prediction: DACS's shade scope grows by about
#   0.34 ms (cost 0 -> 256) and deferred's lighting by about 1.6; the DACS kernels that grow
#   are its shade reductions, each launch 4,096-65,536 lanes.
# grouped, ckmat: as in gpu_twenty_eighth.sh (prepared there, not run).
. "$(dirname "$0")/gpu_env.sh"
for part in "$@"; do
  if [ "$part" = dacsprof ]; then
    for cost in 0 256; do
      prof_args="--scene foliage --shader-cost $cost --top 14 --calls 3"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py dacs \
        $prof_args --scope visibility --scope decide --scope interpolate --scope shade \
        --scope dacs 2>&1 | quiet | tee -a "$OUT/dacsprof.md"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py deferred \
        $prof_args --scope visibility --scope gbuffer --scope plan --scope lighting \
        2>&1 | quiet | tee -a "$OUT/dacsprof.md"
    done
    XLA_FLAGS="--xla_dump_to=/tmp/dacsdump --xla_dump_hlo_as_text" PYTHONPATH=$PWD:/tmp/site \
      timeout -k 5 90 python3 benchmarks/profile_kernels.py dacs --scene foliage \
      --shader-cost 256 --top 4 --calls 1 2>&1 | quiet > /dev/null
    (cd /tmp/dacsdump && tar -czf "$OUT/dacsdump.tar.gz" $(ls | grep after_optimizations.txt))
  else
    OUT=$OUT bash benchmarks/gpu_twenty_eighth.sh "$part"
  fi
done
exit 0
