#!/usr/bin/env bash
# Prepared in the twenty-eighth session (carry [".whl"]). Calls as they ran, one H100 each
# (RESULTS.md, twenty-eighth session; the layer parts have since been folded into layer_bench,
# and split's layers bench then had a 100 s limit):
#   1. bash benchmarks/gpu_twenty_eighth.sh glassprof fits planhlo
#   2. bash benchmarks/gpu_twenty_eighth.sh layers forward   (carry .v: .v/base, f6ec9d1's)
#   3. bash benchmarks/gpu_twenty_eighth.sh split   (carry .v: .v/base and .v/split, not kept)
# Prepared for the next session, one call (carry [".whl", ".v"]):
#   bash benchmarks/gpu_twenty_eighth.sh grouped ckmat scenes1
# after building its two trees here (the device may have neither git nor patch):
#   rm -rf .v/base .v/ckmat && mkdir -p .v/base .v/ckmat
#   git archive HEAD jaxrender | tar -x -C .v/base && cp -r .v/base/jaxrender .v/ckmat/
#   git apply --directory=.v/ckmat benchmarks/variants/checker_mask_stored.patch
# glassprof: forward and object space on glass (5.13 and 4.55 ms, the two worst real-time rows
#   on an H100) and forward on room (3.06-3.11), kernels by scope: where their time goes after
#   the shader moved to per-point components.
# fits, planhlo, scenes1, scenes2: as in gpu_twenty_seventh.sh.
# layers: one launch of the shader at 4096 / 16384 / 65536 / all covered lanes, costs 0 and
#   256, the layers summed over their major axis ([layers, lanes], this tree) against their
#   minor axis (bench_cost_layers.py --layers-minor). DACS's slope was 1.96x deferred's on
#   foliage (fits above) with about the same lanes per invocation (1.41 against 1.37): its
#   launches are small. Prediction: the minor axis brings 4096 lanes within 1.5x of all lanes.
# split: .v/split sums the layers in groups (shade.layer_groups: the most groups that divide
#   the layers with groups x lanes near 2^18), each group a reduction of its own. It split
#   nothing: cost 256 is 257 layers, a prime, so .v/split ran base's program (RESULTS.md).
#   The layers bench in that tree, then foliage's fits of
#   deferred and DACS in .v/base (f6ec9d1's, with the visibility pass alone) and .v/split
#   (costs 0 and 256). The layers bench above found 4096 lanes 10x and 16384 lanes 2x
#   foliage's full-screen cost per evaluation, in either axis order. Prediction: 4096 and
#   16384 lanes within 2x of the full screen, DACS's slope within 1.3x of deferred's (1.96x),
#   deferred's unchanged.
# grouped (prepared, not run: too little device time was left to start a machine): the
#   layers bench with the layers in groups of n // groups (groups x lanes at most 2^18, the
#   layers left over summed after them) and the groups' partial sums stored apart
#   (bench_cost_layers.py --layers-grouped), beside this tree's. Split never ran in groups.
#   Prediction: 4096 and 16384 lanes within 2x of the full screen's cost per evaluation.
# ckmat (prepared, not run): checkerboard with its planned mask stored before its compaction
#   (benchmarks/variants/checker_mask_stored.patch: fusion.materialize), against this tree.
#   planhlo found the plan, neighbour, spatial and temporal tests fused into the compaction's
#   block sums: one multi-output reduction kernel of 0.13 ms a frame writing 13 screen-sized
#   arrays. Images and counts equal on the CPU (foliage, room, glass, 3-frame pans); the
#   checkerboard, skipped-work and program-outputs tests were said to pass in that tree, but
#   run as `PYTHONPATH=.v/ckmat pytest -o pythonpath= ...` they import this checkout's
#   jaxrender (pytest puts the root first); a tree is tested from a copy of tests/ beside it.
#   Prediction: 0.05-0.1 ms a frame faster on foliage and room.
# forward: forward's colours written in its work list's order (dispatch.run_in_order, one
#   contiguous slice a launch) against scattered into a fragment-sized array (.v/base). The
#   scatter took 0.44 ms of glass's 4.83 and 0.20 of room's 2.96 (glassprof). Prediction:
#   0.1-0.3 ms faster on glass and room, the images equal.
. "$(dirname "$0")/gpu_env.sh"
for part in "$@"; do
  if [ "$part" = glassprof ]; then
    prof forward glass 90 fragments alpha_test depth_test quads shade resolve counts \
      transparent lights texture
    prof object_space glass 90 mark_allocate reuse visibility shade resolve counts \
      transparent lights
    prof forward room 70 fragments alpha_test depth_test quads shade resolve counts lights \
      texture
  elif [ "$part" = layers ]; then
    layer_bench layers major
    layer_bench layers minor --layers-minor
  elif [ "$part" = split ]; then
    TREE=$PWD/.v/split layer_bench layers split
    for t in base split; do
      R=$PWD/.v/$t; P="deferred dacs"; [ $t = base ] && P="visibility deferred dacs"
      PYTHONPATH=$R:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
        --scenes foliage --pipelines $P --costs 0 256 --frames 8 --repeats 5 \
        --budget 140 --out "$OUT/split_fits.jsonl" 2>&1 | quiet | grep -v '^{' \
        | sed "s/^/$t: /" | tee -a "$OUT/split_fits.md"
    done
  elif [ "$part" = grouped ]; then
    layer_bench grouped tree
    layer_bench grouped grouped --layers-grouped
  elif [ "$part" = ckmat ]; then
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    grep -q materialize .v/ckmat/jaxrender/pipelines/checkerboard.py || exit 1
    side_by_side ckmat 150 "base ckmat" --scenes foliage room glass --pipelines checkerboard
  elif [ "$part" = forward ]; then
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side forward 150 "base after" --scenes glass room foliage --pipelines forward
  else
    OUT=$OUT bash benchmarks/gpu_twenty_seventh.sh "$part"
  fi
done
exit 0
