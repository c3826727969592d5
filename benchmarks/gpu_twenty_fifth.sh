#!/usr/bin/env bash
# Prepared in the twenty-fifth session (carry [".whl", ".v"]; build .v first:
# benchmarks/variants/prepare.sh), one call:
#   bash benchmarks/gpu_twenty_fifth.sh gbuffer lanes      (about 6 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fifth.sh profile os         (about 3 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fifth.sh final              (about 6 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fifth.sh crossover          (about 2 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fifth.sh dacs               (about 3 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fifth.sh checker            (about 3 minutes; not yet run)
# gbuffer: v24 (593a3ff, the G-buffer as rows of 20 channels) against this tree (one array a
#   field; the sorted blend's first pass unconditional), 8-frame pans, images only: deferred,
#   checkerboard and DACS on room and glass. bench_gbuffer_layout.py gave the fields 0.58x the
#   rows' time on an H100 (0.42 against 0.72 ms); prediction: deferred 0.25-0.3 ms faster a
#   frame on both scenes, checkerboard and DACS less (they pack only the points they shade),
#   glass a further ~0.05 ms (one host read fewer).
# lanes: whether the slopes that differ from deferred's follow the lanes launched, not the
#   points shaded. Object space on foliage launches one 2^18-lane chunk a frame for the few
#   hundred shadels a reusing frame shades (its chunk is sized for the store, 12.4M shadels):
#   costs 0 and 256 at chunk 0 (auto), 65536 and 16384 (prediction: the slope per point falls
#   towards deferred's as the idle lanes go, 2.0x -> about 1.2x). Deferred on foliage compacts
#   its 757k points into half a screen (1.04M lanes): against tiers_fine (compacted sizes at
#   every sixteenth of the screen from 2/16 to 8/16, 778k lanes), prediction: its slope falls
#   towards the visibility buffer's (0.72x deferred's, which launches 786k).
# profile: forward on room (3.63 ms, the one opaque row over 3 ms; its line's intercept is
#   3.48 ms against deferred's 2.36) and deferred on glass (3.35 ms after the G-buffer change),
#   kernels by scope, the largest 25.
# os: object space's chunk sized for half a screen (this tree) against its store (v24) on
#   foliage, thin and glass (prediction from lanes: 0.05-0.1 ms a frame faster at the default
#   shader, where the idle lanes cost little).
# final: this tree on every built-in scene, images only, for the pipelines this session
#   changed (deferred, checkerboard and DACS: the G-buffer's fields; glass: every pipeline,
#   the sorted blend's read), and deferred and object space on foliage at four shader costs.
# crossover: deferred, checkerboard and DACS on foliage at costs 64 and 256 after the G-buffer
#   change (the README's crossovers, 29 and 80 layers, are from before it; cost 0 lies below
#   the lines, so these start at 64).
# checker: checkerboard is now slower than deferred on every opaque scene but room at the
#   default shaders (0.97-2.01 ms against 0.79-1.90). Its half-screen list launched in one
#   dense pass (.v/dense_checker, one host read) against today's chunked dispatch (5 reads on
#   foliage): in the eighteenth session no clear gain; the G-buffer change shortened both
#   passes, so the reads weigh more now. Prediction: dense 0.1-0.2 ms faster on foliage and
#   room, equal on glass.
. "$(dirname "$0")/gpu_env.sh"
S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
for part in "$@"; do
  if [ "$part" = gbuffer ]; then
    side_by_side gbuffer 150 "v24 after" --scenes room glass \
      --pipelines deferred checkerboard dacs
  elif [ "$part" = lanes ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines object_space object_space:chunk=65536 \
      object_space:chunk=16384 --costs 0 256 --frames 8 --repeats 5 --out "$OUT/lanes.jsonl" \
      2>&1 | quiet | grep -v '^{' | tee -a "$OUT/lanes.md"
    for t in tiers_fine after; do
      if [ "$t" = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 100 python3 benchmarks/bench_time_work.py \
        --scenes foliage --pipelines deferred --costs 0 256 --frames 8 --repeats 5 \
        --label "$t" --out "$OUT/lanes.jsonl" 2>&1 | quiet | grep -v '^{' \
        | sed "s/^/$t: /" | tee -a "$OUT/lanes.md"
    done
  elif [ "$part" = os ]; then
    side_by_side os 100 "v24 after" --scenes foliage thin glass --pipelines object_space
  elif [ "$part" = final ]; then
    export PYTHONPATH=$PWD:/tmp/site
    timeout -k 5 300 $S --scenes stripes spheres foliage thin terrain sliver room many_small \
      foliage_wind spheres_spin grass glass --pipelines deferred checkerboard dacs \
      --json "$OUT/final_scenes.json" 2>&1 | quiet | grep '^|' | tee -a "$OUT/final.md"
    timeout -k 5 80 $S --scenes glass --pipelines visbuffer forward object_space \
      --json "$OUT/final_glass.json" 2>&1 | quiet | grep '^|' | tee -a "$OUT/final.md"
    timeout -k 5 140 python3 benchmarks/bench_time_work.py --scenes foliage \
      --pipelines deferred object_space --costs 0 64 256 1024 --frames 8 --repeats 5 \
      --budget 120 --out "$OUT/final_fits.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/final.md"
  elif [ "$part" = crossover ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines deferred checkerboard dacs --costs 64 256 --frames 8 \
      --repeats 5 --budget 130 --out "$OUT/crossover.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/crossover.md"
  elif [ "$part" = dacs ]; then  # crossover's DACS rows (cut by its budget), deferred's again
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 190 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines dacs deferred --costs 64 256 --frames 8 --repeats 5 \
      --budget 175 --out "$OUT/dacs.jsonl" 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/dacs.md"
  elif [ "$part" = checker ]; then
    side_by_side checker 80 "dense_checker after" --scenes foliage room glass \
      --pipelines checkerboard
  elif [ "$part" = profile ]; then
    prof forward room 90 fragments alpha_test depth_test quads shade resolve
    prof deferred glass 90 visibility gbuffer lighting transparent fragments front \
      layer_shading composite sorted_blend
  fi
done
exit 0
