#!/usr/bin/env bash
# Nineteenth session's last device call (2026-12-05), carry [".whl"]:
#   bash benchmarks/gpu_nineteenth.sh
# Deferred with its screen passes in one launch (this checkout's default) against the same
# checkout under JAXRENDER_DISPATCH=blocks (the chunked passes it had before), alternated, on
# four scenes; then what the every-scene call did not reach on glass: the visibility buffer and
# the visibility pass alone.
. "$(dirname "$0")/gpu_env.sh"
D="--frames 16 --rounds 5 --scenes room foliage terrain glass --pipelines deferred"
for round in 1 2; do
  trees deferred.jsonl 100 after $D
  JAXRENDER_DISPATCH=blocks trees deferred_blocks.jsonl 100 after $D
done
trees glass.jsonl 80 after --frames 16 --rounds 5 --scenes glass --pipelines visbuffer
PYTHONPATH=$PWD:/tmp/site timeout 70 python3 benchmarks/bench_time_work.py --scenes glass \
  --pipelines visibility --costs 0 --repeats 15 --out "$OUT/visibility.jsonl" 2>&1 | quiet \
  | tail -3
exit 0
