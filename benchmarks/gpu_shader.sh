#!/usr/bin/env bash
# The shader alone (bench_shader.py) from the tree before this change (.before/, from
# `git archive <commit> jaxrender benchmarks pyproject.toml | tar -x -C .before`) and from this
# one, side by side in one device call. carry: [".whl", ".before"]. Output under $OUT.
. "$(dirname "$0")/gpu_env.sh"
SCENES=${SCENES:-room foliage stripes}
for tree in before after; do
  root=$PWD; [ $tree = before ] && root=$PWD/.before
  PYTHONPATH=$root:/tmp/site timeout -k 5 ${STEP_S:-150} python3 benchmarks/bench_shader.py \
    --scenes $SCENES --label $tree --hlo-dir "$OUT/hlo" --top 6 2>&1 | quiet | tee -a "$OUT/shader.md"
done
grep RESULT "$OUT/shader.md"
