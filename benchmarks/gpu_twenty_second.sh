#!/usr/bin/env bash
# Prepared in the twenty-second session (carry [".whl", ".v"]; build .v first:
# benchmarks/variants/prepare.sh), one call per line:
#   bash benchmarks/gpu_twenty_second.sh parts room glass      (about 5 minutes)
#   bash benchmarks/gpu_twenty_second.sh shared                (about 6 minutes)
#   bash benchmarks/gpu_twenty_second.sh instruments           (about 5 minutes)
#   bash benchmarks/gpu_twenty_first.sh dacs                 (about 3 minutes)
# shared: v20 (c87d91d) against this tree, costs 0 and 256 on foliage and room (or $SCENES),
#   object space and deferred (object space first: a budget cut loses the last rows). The
#   shader-cost layers now read the lights' incoming terms and the point's frame from one
#   store instead of each layer computing them again (CPU, 480x270: slopes -25 to -44% on
#   room, -22 to -39% on foliage). Prediction: lower slopes on the GPU too, most on room
#   (point lights); object space's most of all if its 2.2x slope came from each layer
#   rebuilding parts of its shadel points; cost 0 unchanged (no layers).
# glass: where deferred spends a frame on glass (every pipeline is over 3 ms there): kernels
#   by scope, the largest 30.
# room: where deferred's lighting pass on room goes (0.94 ms on an H200 in the twentieth
#   session; the 64-sample reference shades 64 of it a pixel): surface points, textures,
#   lights and the shadow lookup, the largest 25 kernels.
# instruments: each pipeline's sequence with all its outputs against its images alone
#   (bench_instruments.py): the share of a frame that is the counts and views, not the
#   architecture's work (CPU, 480x270: see RESULTS, twenty-third session).
# parts: one shade() launch over room's and foliage's covered pixels with each effect off in
#   turn (bench_shade_parts.py), and the optimized programs' text kept in $OUT/hlo: how many
#   kernels the shader is split into on the GPU and what they store between them (on the CPU,
#   room's shader stores 902 bytes a point in 93 kernels).
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
prof() {  # prof SCENE SECONDS TOP SCOPE...: deferred's kernels on SCENE by named scope
  local scene=$1 limit=$2 top=$3
  shift 3
  timeout -k 5 "$limit" python3 benchmarks/profile_kernels.py deferred --scene "$scene" \
    --top "$top" --calls 3 $(printf -- '--scope %s ' "$@") 2>&1 | quiet | tee -a "$OUT/profile.md"
}
for part in "$@"; do
  if [ "$part" = shared ]; then
    for t in v20 after; do
      if [ "$t" = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout 175 python3 benchmarks/bench_time_work.py \
        --scenes ${SCENES:-foliage room} --frames 8 --costs 0 256 --repeats 5 --budget 150 \
        --label "$t" --pipelines object_space deferred --out "$OUT/shared.jsonl" --outputs all \
        2>&1 | quiet | grep -v '^{' | sed "s/^/$t: /" | tee -a "$OUT/shared.md"
    done
  elif [ "$part" = glass ]; then
    prof glass 80 30 visibility gbuffer lighting transparent front layer_shading composite \
      sorted_blend
  elif [ "$part" = instruments ]; then
    timeout -k 5 300 python3 benchmarks/bench_instruments.py --scenes thin foliage room \
      --pipelines object_space dacs forward deferred --out "$OUT/instruments.jsonl" 2>&1 \
      | quiet | tee -a "$OUT/instruments.md"
  elif [ "$part" = parts ]; then
    timeout -k 5 150 python3 benchmarks/bench_shade_parts.py --scenes room foliage \
      --out "$OUT/shade_parts.jsonl" --hlo "$OUT/hlo" 2>&1 | quiet | tee -a "$OUT/parts.md"
  elif [ "$part" = room ]; then
    prof room 70 25 visibility gbuffer lighting surface_points texture lights shadow_lookup
  fi
done
exit 0
