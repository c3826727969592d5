#!/usr/bin/env bash
# Thirty-second session. Call 1, one H100 (RESULTS.md): `gpu_thirty_first.sh pairs dacsprof`.
# The session's later tries of this script got no machine (failed starts and refusals used the
# rest of the budget). Prepared for the next session, one call (carry [".whl", ".v"]; first
# .v/base: mkdir -p .v/base && git archive 6b5f13c jaxrender | tar -x -C .v/base; and
# .v/pairs32: mkdir -p .v/pairs32 && git archive HEAD jaxrender | tar -x -C .v/pairs32 &&
# git apply --directory=.v/pairs32 benchmarks/variants/lex_sort_pairs32.patch):
#   bash benchmarks/gpu_thirty_second.sh pairs32 sortcount glassprof dacskern targets
# pairs32 (.v/pairs32): keys of at most 32 bits that today pack with the entry's index into an
#   int64 (forward's quad sort, 19 + 10 + 3 bits on glass; the visibility buffer's two, 27 and
#   31 bits) sorted as a uint32 key beside an int32 index (pair_sort): half the radix passes.
#   The sort bench on forward's quad keys (after, pairs32, after), then side by side with
#   this tree, A B B A, forward and the visibility buffer on glass and foliage. Prediction: forward 0.1-0.25 ms a frame faster on both scenes, the visibility
#   buffer 0.05-0.15; same CPU outputs (tests/test_sorting.py with a 32-bit case passes there).
# sortcount: bench_lex_sort.py in .v/base (two packed int64 sorts) and this tree (pair_sort,
#   adopted from call 1), now listing every custom-call target: call 1's counter found neither
#   a sort nor a cub call in either tree's GPU program, so which sort ran was not read.
#   Prediction: base 2 custom calls naming cub's radix sort and no sort left, this tree 1.
# glassprof: deferred and forward on glass, kernels by scope, now that the composite sorts once
#   (call 1, H100: deferred 2.73-2.84 ms a frame, forward 4.78-4.83): where glass's frame goes.
# dacskern: DACS on foliage at costs 0 and 256, the 30 longest kernels of its shade scope
#   with their launches. Call 1's H100 program (its dacsdump, cost 256) had 20-27 kernels in
#   each shade branch, seven of them `surface_points` stacks (concatenate fusions); call 1
#   here found 80 more launches at cost 256 than at 0. Which of those kernels exist at cost 0 tells
#   whether the stacks are DACS's fixed cost or the layers' (the store of shared values).
# targets: every real-time pipeline on glass and room, on an H200 only (the issue's card; run
#   first there); skipped on an H100, where call 1 measured glass and room side by side.
. "$(dirname "$0")/gpu_env.sh"
on_h200() { nvidia-smi --query-gpu=name --format=csv,noheader | grep -q H200; }
for part in $(targets_first "$*"); do
  if [ "$part" = pairs32 ]; then
    grep -q narrow .v/pairs32/jaxrender/sorting.py || exit 1
    for t in after pairs32 after; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 90 python3 -P benchmarks/bench_lex_sort.py \
        --keys quads 2>&1 | quiet | grep '^|\|^device\|^custom' | sed "s/^/$t: /" \
        | tee -a "$OUT/pairs32_sort.md"
    done
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side pairs32 150 "after pairs32" --scenes glass foliage \
      --pipelines forward visbuffer
  elif [ "$part" = sortcount ]; then
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
  elif [ "$part" = dacskern ]; then
    for cost in 0 256; do
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py dacs \
        --scene foliage --shader-cost $cost --top 6 --calls 3 --scope shade --scope-top 30 \
        2>&1 | quiet | tee -a "$OUT/dacskern.md"
    done
  elif [ "$part" = targets ]; then
    on_h200 || { echo "targets: not an H200, skipped" | tee -a "$OUT/targets.md"; continue; }
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirtieth.sh targets
  fi
  bundle_out
done
exit 0
