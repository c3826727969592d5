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
# Call 2 (carry [".whl", ".v/head37", ".v/fine"]; .v/head37 from `git archive 13f8468
#   jaxrender`, .v/fine this tree with benchmarks/variants/layer_prefix_fine.patch applied):
#   bash benchmarks/gpu_thirty_seventh.sh fwdsplit
# fwdsplit: forward's opaque units shaded with the three-channel shader and its transparent
#   units in a pass of their own over their compacted list (shaded and composited in one
#   launch over its filled prefix), against 13f8468, on glass (A B C C B A with `fine`);
#   then this tree's forward on glass by scope. Room is left out: without transparency its
#   program is the same. Prediction from prof37 (call 1): forward on glass 0.4-0.7 ms a
#   frame faster (the opaque lanes no longer run the opacity; the composite's 64-bit sort
#   covers the 1.56M-entry prefix of 1.23M listed layers, not the 4.15M of the draw list's
#   3.29M fragments: 0.377 ms of cub sorts in call 1's profile); deferred unchanged.
# fine (in fwdsplit): the layer shader's launch over the list's prefix in steps of at most
#   1.25x (benchmarks/variants/layer_prefix_fine.patch): glass's 1,248,672 listed fragments
#   in 1,296,000 lanes, not 1,555,200. Predicted: deferred and forward on glass 0.08-0.13 ms
#   faster (layer shading 0.503 ms over 1.56M lanes, and the composite's sort on the prefix).
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
  elif [ "$part" = fwdsplit ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side fwdsplit 150 "head37 after fine" --scenes glass --pipelines forward deferred
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py forward \
      --scene glass --top 30 --calls 3 --scope-top 6 $(printf -- '--scope %s ' fragments \
      depth_test quads shade resolve counts transparent layer_shading composite sorted_blend) \
      2>&1 | quiet | tee -a "$OUT/fwdsplit_prof.md"
  fi
  bundle_out
done
exit 0
