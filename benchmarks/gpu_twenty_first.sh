#!/usr/bin/env bash
# Prepared in the twentieth session for the next one (carry [".whl"]), one call per line:
#   bash benchmarks/gpu_twenty_first.sh fits      (about 6 minutes)
#   bash benchmarks/gpu_every_scene.sh 1          (then 2, then 3: the targets' table)
# fits: fixed cost and slope on foliage at shader costs 0, 256 and 1024, every pipeline. At 256
#   DACS's shading (21 M layer evaluations) added less than its run-to-run spread; at 1024 it
#   evaluates 83 M. The shader-cost layers now run in blocks above shade.LAYER_LANES
#   layer-lanes (deferred's foliage screen at 256: one loop iteration and 63 layers after it).
#   Prediction: slopes of checkerboard, forward and visbuffer within 25% of deferred's as at
#   256 (TADS was 26% off in one call); DACS's measurable; object space's still about 2x.
#   bash benchmarks/gpu_twenty_first.sh dacs      (build .v first: benchmarks/variants/prepare.sh;
#                                                  carry [".whl", ".v"]; about 3 minutes)
# dacs: DACS against v19 (424a5fe) on foliage, room and thin, alternated twice: its decide and
#   interpolate passes now add their four parents' terms instead of reducing over them (CPU:
#   -21% on foliage, -27% on room). Prediction: 0.1-0.2 ms a frame less on the GPU.
#   bash benchmarks/gpu_twenty_first.sh shared    (carry [".whl", ".v"]; about 7 minutes)
# shared: v20 (c87d91d) against this tree, costs 0 and 256 on foliage and room, deferred,
#   object space and forward: the shader-cost layers now read the lights' incoming terms and
#   the point's frame stored once instead of each layer computing them again (CPU, 480x270:
#   slopes -25 to -44% on room, -22 to -39% on foliage). Prediction: lower slopes on the GPU
#   too, most on room (point lights), and object space's most of all if its 2x slope came
#   from each layer rebuilding parts of its shadel points (gathers from the sheet) that
#   deferred reads from its G-buffer; cost 0 unchanged (no layers).
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
for part in "$@"; do
  if [ "$part" = fits ]; then
    timeout 560 python3 benchmarks/bench_time_work.py --scenes foliage --frames 8 \
      --costs 0 256 1024 --repeats 5 --budget 520 --label blocks --out "$OUT/time_work.jsonl" \
      --pipelines visibility deferred checkerboard dacs forward visbuffer tads object_space \
      2>&1 | quiet | grep -v '^{' | tee -a "$OUT/fits.md"
  elif [ "$part" = dacs ]; then
    for round in 1 2; do
      trees dacs.jsonl 120 "v19 after" --frames 16 --rounds 5 --scenes foliage room thin \
        --pipelines dacs
    done
  elif [ "$part" = shared ]; then
    for t in v20 after; do
      if [ "$t" = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout 270 python3 benchmarks/bench_time_work.py \
        --scenes foliage room --frames 8 --costs 0 256 --repeats 5 --budget 240 --label "$t" \
        --pipelines deferred object_space forward --out "$OUT/shared.jsonl" --outputs all \
        2>&1 | quiet | grep -v '^{' | sed "s/^/$t: /" | tee -a "$OUT/shared.md"
    done
  fi
done
exit 0
