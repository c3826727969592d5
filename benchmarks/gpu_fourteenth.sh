#!/usr/bin/env bash
# Fourteenth session's plan (no machine was lent that session either): the reference's samples
# in passes (one traversal and one shading launch for several samples), side by side with
# one sample a pass, in one device call. Run after gpu_thirteenth.sh (its "after" tree is this
# one, so its reference rows are at the default 8 samples a pass).
#   device run (carry .whl): bash benchmarks/gpu_fourteenth.sh reference
# reference: per-frame ms of the 64-sample reference inside a 2-frame pan, median of 3 rounds,
#   at samples_per_pass 1, 2, 4 and 8 (PASSES) on SEQ_SCENES, with --checksum: the image sums
#   and invocations must be equal across the pass sizes (the CPU tests hold the images equal
#   bit for bit). Prediction (from the ninth session's profile: room's reference ran 9680
#   launches a frame, and on light shaders 0.5 ms a sample went to the raster and launches):
#   stripes and foliage 40-60% faster at 8 than at 1; room, where 64 screens of shading
#   dominate, 10-25% faster.
# msaa: deferred with 1 and 4 samples (the 4 sample positions now share one
#   traversal), 16-frame pan, for comparison with the rows of earlier sessions.
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution ${RES:-1920x1080}"
for part in "$@"; do
  if [ "$part" = reference ]; then
    specs=""
    for n in ${PASSES:-1 2 4 8}; do specs="$specs reference:samples_per_pass=$n"; done
    timeout -k 5 ${LIMIT:-420} $S --frames 2 --rounds 3 \
      --scenes ${SEQ_SCENES:-stripes foliage room thin} --pipelines $specs \
      2>&1 | quiet | grep '^{' | tee -a "$OUT/reference.jsonl"
  elif [ "$part" = msaa ]; then
    timeout -k 5 ${LIMIT:-200} $S --frames 16 --rounds 5 --scenes ${SEQ_SCENES:-foliage room} \
      --pipelines deferred deferred:msaa=4 2>&1 | quiet | grep '^{' \
      | tee -a "$OUT/msaa.jsonl"
  fi
done
exit 0
