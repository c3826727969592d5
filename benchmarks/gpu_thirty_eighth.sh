#!/usr/bin/env bash
# Thirty-eighth session. Call 1 (carry [".whl", ".v/fwdnew", ".v/osnew"]; each .v tree is
# `git archive 8be7c70 jaxrender` with patches of benchmarks/variants applied: fwdnew
# draw_list_on_prefix and layer_texture_once, osnew mark_chunks_once_a_pixel,
# os_transparent_rows_three_quarters and taps_one_index):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_thirty_eighth.sh fwdnew osnew (then prof38 if time)
# Eighteen calls got no machine before it (twelve failed starts, six refusals), so the
# variants run in two groups, not one by one. It ran on an H200 (RESULTS.md, thirty-eighth session): fwdnew adopted
# (0edb623, 394d780; its patches then removed), osnew not (its three patches stay).
# fwdnew: forward and deferred on glass, this tree against fwdnew (A B B A). Deferred's change
#   is the layer shader's alone: the texture filtered once for the radiance and the opacity
#   (offline H100 program: 8 texture gathers in the layer shading, not 16). Predicted:
#   deferred 0.04-0.1 ms a frame faster; forward 0.08-0.2 (the draw list keyed, sorted and
#   derived on its prefix: 0.04-0.1, gpu_thirty_seventh.sh, plus the layer shader's).
# osnew: object space and TADS on glass, this tree against osnew (A B B A): a chunk marked once
#   a pixel (69% fewer marking stores; predicted 0.1-0.14 ms a frame, gpu_thirty_seventh.sh);
#   object space's transparent samples in a branch of three quarters of a screen's rows
#   (glass at 1080p: 1,555,200 rows for 1,230,888 fragments in front, not 2,073,600: the
#   joined list 3.63M rows, not 4.15M; predicted 0.1-0.25 ms); each tap's chunk and lane
#   stored as one shadel index (taps_one_index.patch; the offline H100 program's taps fusion
#   writes s32 and f32 [rows, 8], not s32, s32, pred and f32: 8 bytes a tap, not 13;
#   predicted 0.05-0.1 ms, for TADS too). Together 0.25-0.45 ms faster for object space;
#   its cold compile about 1.4x (launching instructions 832 -> 1085: a third copy of the
#   frame's tail).
# prof38: object space's and forward's 8-frame sequences on glass by scope (a still camera,
#   state carried), each scope's longest kernels: where the frame's time goes inside a
#   sequence, as the rows time it, after object space's taps change (not yet profiled).
# Last call, on an H200: bash benchmarks/gpu_thirty_eighth.sh ten1 ten2 (targets first)
# ten1, ten2: the real-time pipelines on the ten built-in scenes besides glass and room, as the
#   targets part times those two (8-frame pans, 3 rounds, images only); last timed on an H100
#   in the twenty-fourth session (every row under 3 ms, forward's highest 2.97).
. "$(dirname "$0")/gpu_env.sh"
cached_compiles
S=$S8
for part in $(targets_first "$*"); do
  if [ "$part" = targets ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_fifth.sh targets
  elif [ "$part" = ten1 ] || [ "$part" = ten2 ]; then
    scenes="stripes spheres foliage thin terrain"
    [ "$part" = ten2 ] && scenes="sliver many_small foliage_wind spheres_spin grass"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 290 $S --scenes $scenes --pipelines deferred forward \
      checkerboard dacs visbuffer object_space tads --json "$OUT/$part.json" 2>&1 | quiet \
      | grep '^|\|^#' | tee -a "$OUT/$part.md"
  elif [ "$part" = fwdnew ]; then
    side_by_side fwdnew 120 "after fwdnew" --scenes glass --pipelines forward deferred
  elif [ "$part" = osnew ]; then
    side_by_side osnew 110 "after osnew" --scenes glass --pipelines object_space tads
  elif [ "$part" = prof38 ]; then
    p() {  # p PIPELINE SCOPE...: its 8-frame sequence on glass, kernels by scope
      local pipe=$1
      shift
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py "$pipe" \
        --scene glass --frames 8 --top 40 --calls 3 --scope-top 8 \
        $(printf -- '--scope %s ' "$@") 2>&1 | quiet | tee -a "$OUT/prof38.md"
    }
    p object_space mark_allocate reuse visibility shade resolve counts transparent_marking \
      transparent_resolve transparent
    p forward fragments alpha_test depth_test quads shade resolve counts transparent \
      layer_shading composite sorted_blend
  fi
  bundle_out
done
exit 0
