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
