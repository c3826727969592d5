#!/usr/bin/env bash
# Fourteenth session's plan (no machine was lent that session either), side by side in one
# device call each. Run after gpu_thirteenth.sh; both use the trees of
# benchmarks/variants/prepare.sh (carry .whl and .v): "after" is this checkout, v13 the tree
# before the fourteenth session (c298392), blend_loop this one with the blending pass's layers
# in a loop again.
#   bash benchmarks/gpu_fourteenth.sh reference glass msaa   (about 8 minutes)
# reference: per-frame ms of the 64-sample reference inside a 2-frame pan, median of 3 rounds,
#   at samples_per_pass 1, 2, 4 and 8 (PASSES) on SEQ_SCENES, then v13's reference (one sample
#   at a time, the same shader), with --checksum: image sums and invocations must be equal
#   across all of them (the CPU tests hold the images equal bit for bit). Prediction (the ninth
#   session's profile: room's reference ran 9680 launches a frame, and on light shaders
#   ~0.5 ms a sample went to the raster and launches): stripes and foliage 40-60% faster at 8
#   than at 1; room, where 64 screens of shading dominate, 10-25%; glass 2-4x.
# glass: every pipeline on glass, 16-frame pan, for "after", blend_loop and v13. Prediction:
#   after faster than blend_loop by the loop's launches (8 a blending pass), 0.05-0.2 ms.
# msaa: deferred with 1 and 4 samples (the 4 sample positions now share one traversal) for
#   "after" and v13.
. "$(dirname "$0")/gpu_env.sh"
root_of() { if [ "$1" = after ]; then echo "$PWD"; else echo "$PWD/.v/$1"; fi; }
tag() { sed "s/^{/{\"tree\": \"$1\", /"; }
S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution ${RES:-1920x1080} --outputs all"
for part in "$@"; do
  if [ "$part" = reference ]; then
    specs=""
    for n in ${PASSES:-1 2 4 8}; do specs="$specs reference:samples_per_pass=$n"; done
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 ${LIMIT:-300} $S --frames 2 --rounds 3 \
      --scenes ${SEQ_SCENES:-stripes foliage room glass} --pipelines $specs \
      2>&1 | quiet | grep '^{' | tag after | tee -a "$OUT/reference.jsonl"
    PYTHONPATH=$(root_of v13):/tmp/site timeout -k 5 ${LIMIT:-300} $S --frames 2 --rounds 3 \
      --scenes ${SEQ_SCENES:-stripes foliage room glass} --pipelines reference \
      2>&1 | quiet | grep '^{' | tag v13 | tee -a "$OUT/reference.jsonl"
  elif [ "$part" = glass ]; then
    for t in ${TREES:-after blend_loop v13}; do
      PYTHONPATH=$(root_of "$t"):/tmp/site timeout -k 5 ${LIMIT:-150} $S --frames 16 --rounds 5 \
        --scenes glass --pipelines forward deferred visbuffer checkerboard dacs object_space \
        2>&1 | quiet | grep '^{' | tag "$t" | tee -a "$OUT/glass.jsonl"
    done
  elif [ "$part" = msaa ]; then
    for t in after v13; do
      PYTHONPATH=$(root_of "$t"):/tmp/site timeout -k 5 ${LIMIT:-150} $S --frames 16 --rounds 5 \
        --scenes foliage room --pipelines deferred deferred:msaa=4 2>&1 | quiet | grep '^{' \
        | tag "$t" | tee -a "$OUT/msaa.jsonl"
    done
  fi
done
exit 0
