#!/usr/bin/env bash
# Thirty-second session. Call 1, one H100 (RESULTS.md): `gpu_thirty_first.sh pairs dacsprof`.
# Call 2 (carry [".whl", ".v"]; .v/base: git archive 6b5f13c jaxrender | tar -x -C .v/base):
#   bash benchmarks/gpu_thirty_second.sh sortcount glassprof targets
# sortcount: bench_lex_sort.py in .v/base (two packed int64 sorts) and this tree (pair_sort,
#   adopted from call 1), now listing every custom-call target: call 1's counter found neither
#   a sort nor a cub call in either tree's GPU program, so which sort ran was not read.
#   Prediction: base 2 custom calls naming cub's radix sort and no sort left, this tree 1.
# glassprof: deferred and forward on glass, kernels by scope, now that the composite sorts once
#   (call 1, H100: deferred 2.73-2.84 ms a frame, forward 4.78-4.83): where glass's frame goes.
# targets: every real-time pipeline on glass and room, on an H200 only (the issue's card);
#   skipped on an H100, where call 1 measured glass and room side by side.
. "$(dirname "$0")/gpu_env.sh"
on_h200() { nvidia-smi --query-gpu=name --format=csv,noheader | grep -q H200; }
for part in "$@"; do
  if [ "$part" = sortcount ]; then
    grep -q pair_sort .v/base/jaxrender/sorting.py && exit 1
    for t in base after; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 90 python3 -P benchmarks/bench_lex_sort.py 2>&1 \
        | quiet | grep '^|\|^device\|^custom' | sed "s/^/$t: /" | tee -a "$OUT/sortcount.md"
    done
  elif [ "$part" = glassprof ]; then
    prof deferred glass 120 visibility gbuffer lighting transparent fragments front \
      layer_shading composite sorted_blend resolve counts
    prof forward glass 120 fragments alpha_test depth_test quads shade resolve counts \
      transparent composite sorted_blend
  elif [ "$part" = targets ]; then
    on_h200 || { echo "targets: not an H200, skipped" | tee -a "$OUT/targets.md"; continue; }
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirtieth.sh targets
  fi
  bundle_out
done
exit 0
