#!/usr/bin/env bash
# Eleventh session, second call: the unpeeled fragment collection and the unique dispatch and
# fragment scatters, before (.before/) and after, per frame inside a 16-frame pan; a profile
# of deferred on room (its G-buffer scatter) and forward on thin (its copies) after.
#   prepare: mkdir .before && git archive <commit> jaxrender benchmarks pyproject.toml | tar -x -C .before
#   device run (carry .whl, .before): bash benchmarks/gpu_eleventh_b.sh
. "$(dirname "$0")/gpu_env.sh"
LOG=$OUT/eleventh_b.md
SEQ="--frames 16 --rounds 5 --no-single"
PIPES="--pipelines forward deferred visbuffer checkerboard dacs"
for tree in before after; do
  root=$PWD; [ $tree = before ] && root=$PWD/.before
  echo "## $tree" | tee -a "$LOG"
  PYTHONPATH=$root:/tmp/site timeout 200 python3 $root/benchmarks/bench_sequence.py $SEQ $PIPES \
    --scenes thin room foliage terrain 2>&1 | quiet | grep '^{' | tee -a "$LOG"
  PYTHONPATH=$root:/tmp/site timeout 100 python3 $root/benchmarks/bench_sequence.py $SEQ \
    --scenes glass --pipelines forward deferred object_space 2>&1 | quiet | grep '^{' | tee -a "$LOG"
done
export PYTHONPATH=$PWD:/tmp/site
P() { echo "### $*" | tee -a "$LOG"; timeout -k 5 60 python3 benchmarks/profile_kernels.py "$@" \
  2>&1 | quiet | tee -a "$LOG"; }
P deferred --scene room --top 12 --scope visibility --scope gbuffer --scope lighting --scope shade
P forward --scene thin --top 12 --copies --scope fragments --scope depth_test --scope quads --scope shade
