#!/usr/bin/env bash
# Written in the thirty-first session, which got no device machine. Prepared, one call (carry
# [".whl", ".v"]; .v/pairs built as below; targets runs first on an H200):
#   bash benchmarks/gpu_thirty_first.sh pairs dacsprof
# .v/pairs: mkdir -p .v/pairs && git archive HEAD jaxrender | tar -x -C .v/pairs &&
#   git apply --directory=.v/pairs benchmarks/variants/lex_sort_pairs.patch
# pairs: lex_sort's keys that fit one uint64 without the entry's index (the composite's pixel
#   and depth: 21 + 30 bits; forward's transparent sorts too) sorted once, stably, with the
#   index as a second operand, where this tree packs the index in and sorts twice (two int64
#   radix sorts, 16 cub launches on glass). XLA's GPU sort rewriter takes a two-operand sort
#   with an unsigned key to cub's pairs sort; whether it still does once the sort is stable
#   (StableSortExpander's comparator) depends on the XLA version, so bench_lex_sort.py
#   first counts the sorts and cub calls left in each tree's program. Same outputs on the CPU
#   (keys and payload, ties included; tests/test_sorting.py passes in .v/pairs). Prediction: one cub
#   call instead of two and a sort 30-45% faster at 3.1M entries; glass's deferred and
#   checkerboard 0.05-0.1 ms a frame faster, forward 0.1-0.2; room unchanged. If the variant's
#   program keeps a sort that is not cub's, it is a comparison sort: many times slower; drop it.
# Other parts go to gpu_thirtieth.sh (dacsprof, ckfits, ckmat3, ...).
. "$(dirname "$0")/gpu_env.sh"
parts=$(targets_first "$*")
for part in $parts; do
  if [ "$part" = pairs ]; then
    grep -q pair_sort .v/pairs/jaxrender/sorting.py || exit 1
    for t in after pairs after; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 90 python3 -P benchmarks/bench_lex_sort.py 2>&1 \
        | quiet | grep '^|\|^device' | sed "s/^/$t: /" | tee -a "$OUT/pairs_sort.md"
    done
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side pairs 150 "after pairs" --scenes ${PAIRS_SCENES:-glass room} \
      --pipelines ${PAIRS_PIPELINES:-deferred forward checkerboard}
  else
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirtieth.sh "$part"
  fi
  bundle_out
done
exit 0
