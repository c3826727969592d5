#!/usr/bin/env bash
# Thirty-fourth session. Call 1, one H100 (RESULTS.md): `gpu_thirty_third.sh dacsunroll pairs32
# sortcount dacskern glassprof targets`, cut at 600 s in dacskern. Call 2 (carry [".whl"]):
#   bash benchmarks/gpu_thirty_fourth.sh targets fwdprof osprof
# targets: every real-time pipeline on glass and room (8-frame pans, images only) with DACS's
#   levels unrolled and 32-bit keys as a pairs sort (both adopted from call 1), on whatever card
#   comes (the issue's targets are an H200's). Prediction on an H200, from the thirtieth
#   session's table: glass's deferred 2.8-2.95, checkerboard 2.85-3.0, DACS 3.0-3.15, forward
#   4.7-4.9; room's rows all under 3 ms.
# fwdprof, osprof: forward's and object space's frames on glass, kernels by scope (the two
#   largest rows over 3 ms; the twenty-eighth session's profile predates the composite's one
#   sort and the pairs sorts).
. "$(dirname "$0")/gpu_env.sh"
for part in $*; do
  if [ "$part" = targets ]; then
    nvidia-smi --query-gpu=name --format=csv,noheader | tee -a "$OUT/targets.md"
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 330 $S --scenes glass room --pipelines deferred \
      forward checkerboard dacs visbuffer object_space tads --json "$OUT/targets.json" 2>&1 \
      | quiet | grep '^|' | tee -a "$OUT/targets.md"
  elif [ "$part" = uniq ]; then
    grep -q "sentinel + lanes" .v/uniq/jaxrender/pipelines/dispatch.py || exit 1
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side uniq 150 "after uniq" --scenes glass foliage --pipelines forward deferred \
      object_space visbuffer
  elif [ "$part" = switchenv ]; then
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    for mode in blocks switch switch blocks; do
      JAXRENDER_DISPATCH=$mode PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 $S --scenes glass \
        foliage --pipelines forward object_space --json "$OUT/switchenv_$mode.json" 2>&1 \
        | quiet | grep '^|' | sed "s/^/$mode: /" | tee -a "$OUT/switchenv.md"
    done
  elif [ "$part" = dacsparents ]; then
    grep -q level_tables .v/tables/jaxrender/pipelines/dacs.py || exit 1
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side dacsparents 80 "after tables" --scenes foliage --pipelines dacs
  elif [ "$part" = fwdprof ]; then
    prof forward glass 120 fragments alpha_test depth_test quads shade resolve counts \
      transparent composite sorted_blend
  elif [ "$part" = osprof ]; then
    prof object_space glass 120 visibility mark_allocate reuse shade resolve counts \
      transparent_marking transparent_resolve
  fi
  bundle_out
done
exit 0
