#!/usr/bin/env bash
# Time against work inside sequences (bench_time_work.py --frames): the fixed cost and slope of
# every pipeline on foliage, the visibility pass as the floor, each frame timed as studies time
# it. One short device call; rows stream to $OUT/time_work.jsonl. carry: [".whl"]
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=$PWD:/tmp/site PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
timeout ${FITS_S:-175} python3 benchmarks/bench_time_work.py --scenes ${SCENES:-foliage} \
  --frames 8 --costs ${COSTS:-0 64} --repeats 5 --budget ${BUDGET_S:-140} --label sequence \
  --out "$OUT/time_work.jsonl" --pipelines visibility deferred checkerboard dacs forward \
  visbuffer tads object_space 2>&1 | grep -v "^WARNING\|^I0000\|^E0000\|^W0000\|^{" \
  | tee "$OUT/fits.md"
