#!/usr/bin/env bash
# Prepared in the thirty-fourth session for the next one, one call (carry [".whl"]), on the
# H200 the issue names if one comes (ask for kind nvidia-h200), else an H100:
#   bash benchmarks/gpu_thirty_fifth.sh targets fits
# targets: every real-time pipeline on glass and room (8-frame pans, images only), as
#   gpu_thirty_fourth.sh's (call 2 there ran on an H100: glass deferred 2.823, checkerboard
#   2.974, DACS 3.193, visbuffer 3.135, forward 4.743, object space 4.550; room forward 3.256).
#   Prediction on an H200: glass's deferred and checkerboard under 3 ms, DACS 3.0-3.2.
# fits: the visibility pass alone, deferred and DACS on foliage at costs 0 and 256 (8-frame
#   sequences): DACS's fixed cost and slope with its levels unrolled and its parents computed.
#   Before (H100, 2026-12-06): DACS 1.20 ms above the visibility pass, slope 1.96x deferred's.
#   Prediction: 0.95-1.1 ms above it, slope 1.6-2.0x (the unrolled levels spare host reads,
#   a cost every frame pays, not one per point).
# Call 1 ran `targets fits` on an H100 (RESULTS.md, thirty-fifth session). Call 2:
#   bash benchmarks/gpu_thirty_fifth.sh glassprof
# glassprof: deferred's frame on glass and on room, and DACS's on glass, kernels by scope with
#   each scope's longest kernels: what glass adds to every pipeline that runs the transparent
#   pass (deferred on glass 2.75 ms against 1.61 on room, H100, call 1).
# Last call (carry [".whl", ".v/s34"]): bash benchmarks/gpu_thirty_fifth.sh last35
# last35: TADS on glass (it now runs the transparent pass) beside deferred, then forward on
#   room A B B A, s34 against after (two host reads fewer a frame: the fragment list peels its
#   first chunk alone). Predictions: TADS on glass 2.9-3.2 ms (room's 1.83 plus deferred's
#   glass-minus-room 1.14); forward on room 0.04-0.1 ms faster.
# Call 4 (not run: no machine came): bash benchmarks/gpu_thirty_fifth.sh abba35
# abba35: call 3's s34 against after, A B B A (ORDERS=4: twice), 16-frame pans, 5 rounds:
#   call 3's passes of one tree differed by up to 0.14 ms, more than the changes predicted.
#   PIPES="deferred forward" leaves DACS (the longest compile) out.
# Call 3 (carry [".whl", ".v/s34", ".v/wp"]): bash benchmarks/gpu_thirty_fifth.sh after35
# after35: glass's deferred, DACS and forward, A B B A over three trees: s34 (this session's
#   start, 21322fd), wp (DACS's warp counts in closed form, fragment lists peeling their
#   first chunk alone) and after (wp, and the composite's factors stored as one row an entry
#   before its sort). JAX's persistent cache serves each tree's second pass.
#   Predictions: wp against s34, DACS 0.05-0.15 ms faster (20 loop steps and their copies
#   fewer), deferred and forward 0.02-0.06 (one host read fewer a fragment list); after
#   against wp, deferred, DACS and forward 0.05-0.12 faster (the sort's gather).
. "$(dirname "$0")/gpu_env.sh"
for part in $*; do
  if [ "$part" = targets ]; then
    OUT=$OUT bash benchmarks/gpu_thirty_fourth.sh targets
  elif [ "$part" = fits ]; then
    time_work fits 240 --scenes foliage --pipelines visibility deferred dacs --costs 0 256 \
      --frames 8 --repeats 5 --budget 220
  elif [ "$part" = after35 ]; then
    cached_compiles
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side after35 220 "s34 wp after" --scenes glass --pipelines deferred dacs forward
  elif [ "$part" = last35 ]; then
    cached_compiles
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 $S --scenes glass --pipelines tads deferred \
      --json "$OUT/tads_glass.json" 2>&1 | quiet | grep '^|' | tee -a "$OUT/tads_glass.md"
    bundle_out
    if [ ! -d .v/s34/jaxrender ]; then
      echo "no .v/s34: mkdir -p .v/s34 && git archive 21322fd jaxrender | tar -x -C .v/s34"
      exit 1
    fi
    S="$S --frames 16 --rounds 5"
    side_by_side fwdroom 60 "s34 after" --scenes room --pipelines forward
  elif [ "$part" = abba35 ]; then
    cached_compiles
    S="python3 benchmarks/bench_sequence.py --frames 16 --rounds 5 --no-single --outputs images"
    ORDERS=${ORDERS:-2} side_by_side abba35 150 "s34 after" --scenes glass --pipelines \
      ${PIPES:-deferred dacs forward}
  elif [ "$part" = glassprof ]; then
    for case in "deferred glass" "deferred room" "dacs glass"; do
      set -- $case
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/profile_kernels.py "$1" \
        --scene "$2" --top 30 --calls 3 --scope-top 4 $(printf -- '--scope %s ' visibility \
        gbuffer lighting decide transparent fragments layer_shading composite sorted_blend \
        counts lights texture shadow_lookup surface_points) 2>&1 | quiet \
        | tee -a "$OUT/glassprof.md"
    done
  fi
  bundle_out
done
exit 0
