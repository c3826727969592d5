#!/usr/bin/env bash
# Eleventh session, one device call: glass (transparent layers) before/after the radix-sorted
# transparent composite (the old tree in .before/), every pipeline inside a 16-frame pan and
# the reference in a 2-frame one; then kernel profiles of what is left, copies named.
#   prepare: mkdir .before && git archive <commit> jaxrender benchmarks pyproject.toml | tar -x -C .before
#   device run (carry .whl, .before): bash benchmarks/gpu_eleventh.sh
. "$(dirname "$0")/gpu_env.sh"
LOG=$OUT/eleventh.md
SEQ="--frames 16 --rounds 5 --no-single --scenes glass"
PIPES="--pipelines deferred forward checkerboard visbuffer dacs object_space"
REF="--frames 2 --rounds 3 --no-single --scenes glass --pipelines reference"
for tree in before after; do
  root=$PWD; [ $tree = before ] && root=$PWD/.before
  echo "## $tree" | tee -a "$LOG"
  PYTHONPATH=$root:/tmp/site timeout 150 python3 $root/benchmarks/bench_sequence.py $SEQ $PIPES \
    2>&1 | quiet | grep '^{' | tee -a "$LOG"
  PYTHONPATH=$root:/tmp/site timeout 90 python3 $root/benchmarks/bench_sequence.py $REF \
    2>&1 | quiet | grep '^{' | tee -a "$LOG"
done
export PYTHONPATH=$PWD:/tmp/site
P() { echo "### $*" | tee -a "$LOG"; timeout -k 5 60 python3 benchmarks/profile_kernels.py "$@" \
  2>&1 | quiet | tee -a "$LOG"; }
SH="--scope shade --scope texture --scope lights"
P deferred --scene glass --top 24 --copies --scope visibility --scope gbuffer --scope transparent --scope sorted_blend $SH
P forward --scene thin --top 24 --copies --scope fragments --scope depth_test --scope quads --scope resolve --scope counts $SH
P forward --scene room --top 16 --copies --scope fragments --scope depth_test --scope quads --scope resolve --scope counts $SH
