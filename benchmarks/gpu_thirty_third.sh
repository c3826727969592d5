#!/usr/bin/env bash
# Thirty-third session, one call (carry [".whl", ".v"]; build .v first, as gpu_thirty_second.sh's
# header says, and .v/dacs_unroll: mkdir -p .v/dacs_unroll && git archive HEAD jaxrender |
# tar -x -C .v/dacs_unroll && git apply --directory=.v/dacs_unroll
# benchmarks/variants/dacs_unrolled.patch; and .v/gbrow and .v/switchout the same way with
# benchmarks/variants/gbuffer_one_store.patch and switch_values_out.patch):
#   bash benchmarks/gpu_thirty_third.sh dacsunroll pairs32 sortcount dacskern glassprof targets
# dacsunroll (.v/dacs_unroll): DACS's steps unrolled in Python instead of a fori_loop, one step
#   a level, each sized to its own level (a screen of entries decided, not 1.5) and without the
#   loop's host read per step. Side by side with this tree, A B B A, on foliage and
#   glass. On the CPU (640x360, 4 frames, this machine's 2 cores) it took 53.8 and 77.7 ms a
#   frame against 59.4 and 83.5 on foliage and room, and compiled in 45 and 61 s against 27
#   and 28. Prediction: 0.15-0.35 ms a frame faster, compile 1.5-2.5x longer.
#   In the same runs .v/gbrow: `shade_through` stores its G-buffer fields in one store
#   (`materialize_all`) instead of behind an optimization barrier, which the H100's dump of
#   call 1 (thirty-second session) showed as seven concatenate kernels per launch of DACS's
#   shading (the seven "surface_points stacks"). Prediction: 0.05-0.15 ms a frame faster
#   (about 36 fewer launches over six steps), the same images.
#   And .v/switchout: `dispatch.run`'s switch returns the launch's values, padded to the
#   largest launch, and scatters them after the conditional; compiled offline for an H100
#   (offline_kernels.py), DACS on foliage then has no copy of its f32[2073600,3] image left
#   (10 before: one in each of the switch's nine branches and one in the loop body), where
#   on the CPU it was 26% slower. Prediction: 0.1-0.2 ms a frame faster on the GPU.
# The other parts are gpu_thirty_second.sh's (targets runs first on an H200, skipped on an H100).
. "$(dirname "$0")/gpu_env.sh"
for part in $(targets_first "$*"); do
  if [ "$part" = dacsunroll ]; then
    grep -q "Unrolled" .v/dacs_unroll/jaxrender/pipelines/dacs.py || exit 1
    grep -q "materialize_all(\*gbuffer" .v/gbrow/jaxrender/pipelines/gbuffer.py || exit 1
    grep -q "_run_switch" .v/switchout/jaxrender/pipelines/dispatch.py || exit 1
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side dacsunroll 150 "after switchout gbrow dacs_unroll" --scenes foliage glass \
      --pipelines dacs
  elif [ "$part" = dacsquick ]; then
    # dacsunroll on foliage alone, for a call with little device time left.
    grep -q "Unrolled" .v/dacs_unroll/jaxrender/pipelines/dacs.py || exit 1
    grep -q "materialize_all(\*gbuffer" .v/gbrow/jaxrender/pipelines/gbuffer.py || exit 1
    grep -q "_run_switch" .v/switchout/jaxrender/pipelines/dispatch.py || exit 1
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side dacsquick 100 "after switchout gbrow dacs_unroll" --scenes foliage \
      --pipelines dacs
  else
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_second.sh "$part"
  fi
  bundle_out
done
exit 0
