#!/usr/bin/env bash
# One device call: TAA's kernels inside an 8-frame sequence (deferred, spheres_spin, 1920x1080)
# with this tree and with the code before (carried as .before/jaxrender), per named scope; then
# the time_follows_work study (resumable; a run cut by the limit keeps its rows), tarred.
#   device run (carry .whl and .before): bash benchmarks/gpu_final.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
SITE=${SITE:-/tmp/site}
export PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
now=$PWD:$SITE; before=$PWD/.before:$SITE
for v in now before; do
  for s in "" "--set taa=true"; do
    PYTHONPATH=${!v} timeout 70 python3 benchmarks/profile_kernels.py deferred \
      --scene spheres_spin $s --frames 8 --top 0 --calls 5 --scope taa --scope taa_history \
      --scope taa_reproject --scope motion_vectors 2>&1 | quiet | grep "wall\|scope" \
      | sed "s/^/[$v] /" | tee -a "$OUT/taa_profile.md"
  done
done
PYTHONPATH=$now timeout ${STUDY_S:-400} python3 -m jaxrender study time_follows_work \
  --out "$OUT/tw" --no-progress 2>&1 | quiet | tail -60
tar -czf "$OUT/time_follows_work.tgz" -C "$OUT" tw && rm -rf "$OUT/tw"
