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
# Call 2 (carry [".whl", ".v/head37", ".v/split", ".v/fine"]; .v/head37 from `git archive
#   13f8468 jaxrender`, .v/split from `git archive 7756b16 jaxrender`, .v/fine this tree with
#   benchmarks/variants/layer_prefix_fine.patch applied):
#   bash benchmarks/gpu_thirty_seventh.sh fwdsplit
# fwdsplit: forward on glass in four trees, A B C D D C B A: 13f8468; split (7756b16: its
#   opaque units shaded with the three-channel shader, its transparent units compacted and
#   shaded and composited in one launch over that list's prefix); after (this tree: its draw
#   list holds the opaque triangles alone, and the transparent ones go through the shared
#   transparent pass); fine (after, with the layer shader's launch over the transparent list's
#   prefix in steps of at most 1.25x: glass's 1,248,672 listed fragments in 1,296,000 lanes,
#   not 1,555,200). Then deferred on glass, after against fine (A B B A), and this tree's
#   forward on glass by scope. Room is left out: without transparency its program is the
#   same in all four. Predictions from prof37 (call 1), ms a frame on glass: split 0.4-0.7
#   faster than 13f8468 (the opaque lanes no longer run the opacity; the composite's 64-bit
#   sort covers a 1.56M-entry prefix, not the draw list's 4.15M: 0.377 ms of cub sorts);
#   after 0.2-0.4 faster than split (the sort, depth test and derived fields over a 2.07M
#   prefix of 2.05M opaque fragments, not 4.15M of 3.29M; the transparent list's raster
#   0.18 more); fine 0.08-0.13 faster than after, for deferred too.
# Call 3 (carry [".whl", ".v/base_os"]; .v/base_os from `git archive b186e57 jaxrender`):
#   bash benchmarks/gpu_thirty_seventh.sh ostaps
# ostaps: object space on glass, b186e57 against this tree (A B B A): the allocation's taps
#   carried out of its bias loop instead of computed again. Predicted 0.1-0.25 ms a frame
#   faster (call 1, H100: mark/allocate 0.824 ms with two 0.24 ms fusions of [4147200, 8]
#   taps; the offline program now holds one of them).
# Prepared for a later call, not run (carry [".whl", ".v/markonce"]; .v/markonce this tree with
#   benchmarks/variants/mark_chunks_once_a_pixel.patch applied):
#   bash benchmarks/gpu_thirty_seventh.sh markonce
# markonce: object space on glass and room, this tree against markonce (A B B A): a chunk
#   marked once a pixel (69% fewer marking stores, CPU count). Predicted 0.1-0.14 ms a frame
#   faster on glass.
#   drawprefix (carry .v/drawprefix: this tree with benchmarks/variants/draw_list_on_prefix.patch):
#   forward on glass and room against it (A B B A); predicted 0.04-0.1 ms a frame faster.
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
    side_by_side fwdsplit 100 "head37 split after fine" --scenes glass --pipelines forward
    bundle_out
    side_by_side fwdsplit_def 120 "after fine" --scenes glass --pipelines deferred
    bundle_out
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py forward \
      --scene glass --top 30 --calls 3 --scope-top 6 $(printf -- '--scope %s ' fragments \
      depth_test quads shade resolve counts transparent layer_shading composite sorted_blend) \
      2>&1 | quiet | tee -a "$OUT/fwdsplit_prof.md"
  elif [ "$part" = ostaps ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side ostaps 75 "base_os after" --scenes glass --pipelines object_space
  elif [ "$part" = markonce ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side markonce 90 "after markonce" --scenes glass room --pipelines object_space
  elif [ "$part" = drawprefix ]; then
    export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
      JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side drawprefix 90 "after drawprefix" --scenes glass room --pipelines forward
  fi
  bundle_out
done
exit 0
