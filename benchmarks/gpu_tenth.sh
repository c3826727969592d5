#!/usr/bin/env bash
# Tenth session, one device call: object space before/after its counts change (per-frame time
# inside a 16-frame sequence; the old tree in .before/), then time against work on foliage
# (bench_time_work.py: every pipeline, TADS too, at shader costs 0, 16 and 64; the fits).
#   prepare: mkdir .before && git archive <commit> jaxrender benchmarks pyproject.toml | tar -x -C .before
#   device run (carry .whl, .before): bash benchmarks/gpu_tenth.sh
. "$(dirname "$0")/gpu_env.sh"
ARGS="--frames 16 --rounds 5 --no-single --scenes thin terrain room foliage --pipelines object_space"
LOG=$OUT/tenth.md
echo "## before" | tee -a "$LOG"
PYTHONPATH=$PWD/.before:/tmp/site timeout 90 python3 .before/benchmarks/bench_sequence.py $ARGS \
  2>&1 | quiet | grep '^{' | tee -a "$LOG"
echo "## after" | tee -a "$LOG"
PYTHONPATH=$PWD:/tmp/site timeout 90 python3 benchmarks/bench_sequence.py $ARGS \
  2>&1 | quiet | grep '^{' | tee -a "$LOG"
echo "## time against work" | tee -a "$LOG"
PYTHONPATH=$PWD:/tmp/site timeout 260 python3 benchmarks/bench_time_work.py --scenes foliage \
  --costs 0 16 64 --repeats 7 --budget 235 --label tenth --out "$OUT/time_work.jsonl" \
  --pipelines visibility forward deferred visbuffer checkerboard dacs object_space tads \
  2>&1 | quiet | grep -v '^{' | tee -a "$LOG"
