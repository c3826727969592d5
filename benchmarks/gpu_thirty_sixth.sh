#!/usr/bin/env bash
# Thirty-sixth session. Call 1 (carry [".whl", ".v/s34"]; ask for kind nvidia-h200):
#   bash benchmarks/gpu_thirty_sixth.sh fwdprof fwdmodes last35
# fwdprof: forward's frame on glass and room, kernels by scope with each scope's longest
#   kernels: where its 4.7 ms on glass (H100) go beyond deferred's 2.75 at 5% more shading
#   (3,236,406 units against 3,077,036, CPU counts at 1080p). Thirty-fourth session (H100):
#   shade 1.48, fragments 0.87, depth test 0.48; its longest kernel the shading loop's
#   scatter fusion (0.44 ms in 3 launches).
# fwdmodes: forward on glass and room with its work lists launched in each JAXRENDER_DISPATCH
#   mode (blocks, the default; switch; binary), in the order A B C C B A. Forward's shading
#   runs 13 chunks of 2^18 lanes on glass (3 blocks of 4, then 1) and 8 on room; switch
#   launches them at once (one read; glass's 3.24M units in 4.19M lanes, room's 2.09M in
#   2.10M), binary in one launch per set bit (glass 3, room 1). Prediction: room 0.05-0.15 ms
#   faster under switch or binary (host reads and launches fewer, no idle lanes more);
#   glass within 0.1 of blocks (23% more lanes against five reads fewer).
# last35: gpu_thirty_fifth.sh's (TADS on glass beside deferred; forward on room, s34 against
#   this tree, A B B A).
# Call 1 ran `fwdprof fwdmodes last35` on an H100 (RESULTS.md, thirty-sixth session). Call 2
#   (carry [".whl", ".v/base36"]; .v/base36 from `git archive 8c6a21f jaxrender`):
#   bash benchmarks/gpu_thirty_sixth.sh rowsprof rows36
# rowsprof: this tree's forward and deferred on glass, kernels by scope, beside
#   call 1's profiles of 8c6a21f's forward: shader results computed whole (fusion.whole_rows)
#   before the dispatch's scatter and the composite's gather, which had fused the shader and
#   ran it once per channel (the offline H100 program: the lights inside the scatter, 372 of
#   its 535 instructions), and materialize a barrier on a GPU. Predicted: forward's shade
#   scope 1.48 -> 0.7-0.9 ms on glass, 1.19 -> 0.7-0.8 on room; deferred's composite on glass
#   0.41 -> 0.25-0.3 (its 0.205 ms gather held the layer shader).
# rows36: base36 against this tree, A B B A: deferred, forward and the visibility buffer
#   on glass and room (checkerboard left out: the device time left).
# rowsmin: what fits ~300 s of device time: rows36 for forward on glass and room and deferred
#   on glass (A B B A), then forward's profile on glass alone.
# textaps: the texture filter's addresses and weights computed whole before its texels are
#   read (benchmarks/variants/texture_taps_whole.patch, prepared without device time), A B B A
#   against this tree: deferred and forward on glass and room. Prepare the tree here:
#   mkdir -p .v/textaps && git archive HEAD jaxrender | tar -x -C .v/textaps &&
#   patch -d .v/textaps -p1 < benchmarks/variants/texture_taps_whole.patch  (carry .v/textaps)
#   The offline H100 program (jax 0.10.2) of forward on glass: texture instructions a point
#   776 -> 459 (the addresses once a point, not once a channel and again for the opacity); the
#   texels are still read a channel at a time, and 11 values a point are stored and read back.
#   Predicted: within +-0.1 ms a frame either way (integer arithmetic saved against ~44 bytes
#   a point more traffic); adopt only if faster on both scenes in both passes.
# On an H200, `targets` (issue 23's rows) runs first (gpu_env.sh's targets_first).
. "$(dirname "$0")/gpu_env.sh"
for part in $(targets_first "$*"); do
  if [ "$part" = targets ] || [ "$part" = last35 ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_fifth.sh "$part"
  elif [ "$part" = fwdmodes ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 16 --rounds 5 --no-single --outputs images"
    for mode in blocks switch binary binary switch blocks; do
      JAXRENDER_DISPATCH=$mode PYTHONPATH=$PWD:/tmp/site timeout -k 5 100 $S --scenes glass \
        room --pipelines forward 2>&1 | quiet | grep '^|' | sed "s/^/$mode: /" \
        | tee -a "$OUT/fwdmodes.md"
    done
  elif [ "$part" = rowsprof ]; then
    for case in "forward glass" "deferred glass"; do
      set -- $case
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py "$1" \
        --scene "$2" --top 20 --calls 3 --scope-top 5 $(printf -- '--scope %s ' fragments \
        depth_test shade lighting gbuffer transparent layer_shading composite sorted_blend) \
        2>&1 | quiet | tee -a "$OUT/rowsprof.md"
    done
  elif [ "$part" = rows36 ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side rows36 150 "base36 after" --scenes glass room --pipelines deferred forward \
      visbuffer
  elif [ "$part" = rowsmin ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side rowsmin 100 "base36 after" --scenes glass room --pipelines forward
    side_by_side rowsmin_def 60 "base36 after" --scenes glass --pipelines deferred
    prof forward glass 90 fragments depth_test shade lighting
  elif [ "$part" = textaps ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side textaps 150 "after textaps" --scenes glass room --pipelines deferred forward
  elif [ "$part" = fwdprof ]; then
    for scene in glass room; do
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/profile_kernels.py forward \
        --scene "$scene" --top 30 --calls 3 --scope-top 6 $(printf -- '--scope %s ' fragments \
        alpha_test depth_test quads shade resolve counts transparent sorted_blend) 2>&1 \
        | quiet | tee -a "$OUT/fwdprof.md"
    done
  fi
  bundle_out
done
exit 0
