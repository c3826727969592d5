#!/usr/bin/env bash
# Prepared in the twenty-fourth session (carry [".whl"]), one call per line:
#   bash benchmarks/gpu_twenty_fourth.sh scenes1          (about 7 minutes)
#   bash benchmarks/gpu_twenty_fourth.sh scenes2          (about 7 minutes)
#   bash benchmarks/gpu_twenty_fourth.sh fits             (about 6 minutes; ran 2026-12-06)
#   bash benchmarks/gpu_twenty_fourth.sh gbuffer roomfits  (about 8 minutes; not yet run)
#   bash benchmarks/gpu_twenty_fourth.sh fits4            (about 6 minutes; not yet run)
# Every pipeline's time here is of a program that returns the images alone (`--outputs
# images`, the new default of the benches and studies): the counts and views are no longer
# part of a frame. (The visibility pass and the G-buffer layouts have no counts to leave out.)
# scenes1, scenes2: every pipeline's per-frame time inside an 8-frame pan at 1920x1080 on every
#   built-in scene with its default shader (issue 23: at most 3 ms each), and (scenes1) the
#   visibility pass alone on each scene, the floor of the fixed costs. Prediction from the
#   twenty-third session's ratios (H100): TADS on thin 3.2 -> 1.9 ms, object space on thin
#   3.2 -> 2.6 and on foliage 3.0 -> 2.5; deferred and checkerboard within 5% of before.
# fits: frame time against shading work at shader costs 0 and 256 on foliage and room (8-frame
#   pans), each pipeline's fixed cost and slope without the counts (room's rows but forward's
#   ran out of the budget: roomfits runs them).
# fits4: deferred, the visibility buffer and object space on foliage at four shader costs (0,
#   64, 256, 1024): with two costs their slopes (0.60x and 2.29x deferred's) have no standard
#   error; four tell a slope from noise and check the line is one.
# gbuffer: deferred's attribute pass in five G-buffer layouts on room and glass
#   (bench_gbuffer_layout.py). Today's rows are one 0.55 ms concatenation kernel on an H100;
#   prediction: one array a field, or the fields stored before the rows are packed, at least
#   2x faster, since neither leaves each channel's thread to recompute the point.
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
ONE="stripes spheres foliage thin terrain sliver room many_small"
TWO="foliage_wind spheres_spin grass glass"
S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
for part in "$@"; do
  if [ "$part" = scenes1 ]; then
    timeout -k 5 70 python3 benchmarks/bench_time_work.py --scenes $ONE $TWO \
      --pipelines visibility --costs 0 --frames 8 --repeats 9 --out "$OUT/visibility.jsonl" \
      2>&1 | quiet | grep -v '^{' | tee "$OUT/scenes1.md"
    timeout -k 5 420 $S --scenes $ONE --json "$OUT/scenes1.json" 2>&1 | quiet \
      | tee -a "$OUT/scenes1.md"
  elif [ "$part" = scenes2 ]; then
    timeout -k 5 480 $S --scenes $TWO --json "$OUT/scenes2.json" 2>&1 | quiet \
      | tee -a "$OUT/scenes2.md"
  elif [ "$part" = fits ]; then
    timeout -k 5 480 python3 benchmarks/bench_time_work.py --scenes ${SCENES:-foliage room} \
      --pipelines forward deferred visbuffer checkerboard dacs object_space tads \
      --costs 0 256 --frames 8 --repeats 5 --budget 420 --out "$OUT/fits.jsonl" 2>&1 \
      | quiet | grep -v '^{' | tee -a "$OUT/fits.md"
  elif [ "$part" = roomfits ]; then
    timeout -k 5 330 python3 benchmarks/bench_time_work.py --scenes room \
      --pipelines deferred checkerboard dacs tads visbuffer object_space --costs 0 64 \
      --frames 8 --repeats 5 --budget 280 --out "$OUT/roomfits.jsonl" 2>&1 \
      | quiet | grep -v '^{' | tee -a "$OUT/roomfits.md"
  elif [ "$part" = fits4 ]; then
    timeout -k 5 400 python3 benchmarks/bench_time_work.py --scenes foliage \
      --pipelines deferred visbuffer object_space --costs 0 64 256 1024 --frames 8 \
      --repeats 5 --budget 360 --out "$OUT/fits4.jsonl" 2>&1 \
      | quiet | grep -v '^{' | tee -a "$OUT/fits4.md"
  elif [ "$part" = gbuffer ]; then
    timeout -k 5 150 python3 benchmarks/bench_gbuffer_layout.py --scenes room glass 2>&1 \
      | quiet | tee -a "$OUT/gbuffer.md"
  fi
done
exit 0
