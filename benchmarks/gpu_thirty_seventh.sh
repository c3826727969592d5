#!/usr/bin/env bash
# Thirty-seventh session. Call 1 (carry [".whl", ".v/textaps"]):
#   bash benchmarks/gpu_thirty_seventh.sh prof37 textaps
# prof37: glass's frame by scope, each scope's longest kernels, for forward (4.7 ms on an
#   H100, deferred 2.65), deferred (its transparent pass shared by every pipeline on glass:
#   1,248,672 listed fragments, 1,230,888 in front, shaded in a 1,555,200-entry prefix) and
#   object space (4.3-4.5 ms). What the next change aims at is read off these.
# textaps: gpu_thirty_sixth.sh's, glass only (forward and deferred, A B B A): the texture
#   filter's taps computed whole (benchmarks/variants/texture_taps_whole.patch; build
#   .v/textaps as that script's header says). Predicted within +-0.1 ms a frame.
. "$(dirname "$0")/gpu_env.sh"
for part in $(targets_first "$*"); do
  if [ "$part" = targets ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_fifth.sh targets
  elif [ "$part" = prof37 ]; then
    p() {  # p PIPELINE SCOPE...: its frame on glass, kernels by scope
      local pipe=$1
      shift
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/profile_kernels.py "$pipe" \
        --scene glass --top 30 --calls 3 --scope-top 6 $(printf -- '--scope %s ' "$@") 2>&1 \
        | quiet | tee -a "$OUT/prof37.md"
    }
    p forward fragments alpha_test depth_test quads shade resolve counts transparent \
      sorted_blend
    p deferred visibility gbuffer plan lighting resolve counts transparent fragments \
      layer_shading composite sorted_blend
    p object_space mark_allocate reuse visibility shade resolve counts transparent_marking \
      transparent_resolve transparent
  elif [ "$part" = textaps ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side textaps 120 "after textaps" --scenes glass --pipelines deferred forward
  fi
  bundle_out
done
exit 0
