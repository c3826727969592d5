#!/usr/bin/env bash
# Time against work inside sequences (bench_time_work.py --frames): the fixed cost and slope of
# every pipeline on foliage, the visibility pass as the floor, each frame timed as studies time
# it. One short device call; rows stream to $OUT/time_work.jsonl. carry: [".whl"]
# Costs 0 and 256 by default: at 64 the shading added less than the run-to-run spread on an
# H100 (RESULTS.md, nineteenth session).
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
timeout ${FITS_S:-175} python3 benchmarks/bench_time_work.py --scenes ${SCENES:-foliage} \
  --frames 8 --costs ${COSTS:-0 256} --repeats 5 --budget ${BUDGET_S:-140} --label sequence \
  --out "$OUT/time_work.jsonl" --pipelines visibility deferred checkerboard dacs forward \
  visbuffer tads object_space 2>&1 | quiet | grep -v '^{' | tee "$OUT/fits.md"
