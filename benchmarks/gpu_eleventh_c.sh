#!/usr/bin/env bash
# Eleventh session, third call: deferred before/after its G-buffer rows in list order (the old
# tree in .before/), then every pipeline on every built-in scene inside a 16-frame pan (the
# every-scene table, as gpu_every_scene.sh without its visibility floor).
#   prepare: mkdir .before && git archive <commit> jaxrender benchmarks pyproject.toml | tar -x -C .before
#   device run (carry .whl, .before): bash benchmarks/gpu_eleventh_c.sh
. "$(dirname "$0")/gpu_env.sh"
LOG=$OUT/eleventh_c.md
SEQ="--frames 16 --rounds 5 --no-single"
for tree in before after; do
  root=$PWD; [ $tree = before ] && root=$PWD/.before
  echo "## deferred $tree" | tee -a "$LOG"
  PYTHONPATH=$root:/tmp/site timeout 60 python3 $root/benchmarks/bench_sequence.py $SEQ \
    --pipelines deferred --scenes room foliage thin glass 2>&1 | quiet | grep '^{' | tee -a "$LOG"
done
echo "## every scene" | tee -a "$LOG"
export PYTHONPATH=$PWD:/tmp/site
S="python3 benchmarks/bench_sequence.py $SEQ"
timeout 230 $S --scenes stripes spheres foliage thin terrain sliver 2>&1 | quiet | grep '^{' \
  | tee -a "$LOG"
timeout 230 $S --scenes room many_small foliage_wind spheres_spin grass glass 2>&1 | quiet \
  | grep '^{' | tee -a "$LOG"
