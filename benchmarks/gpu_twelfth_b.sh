#!/usr/bin/env bash
# Twelfth session, second call: DACS's idle lanes. Each level launches its list in chunks of
# the largest level's size (65536 lanes at 1080p) in the default loop, so a level needing 16k
# points evaluates 65536 lanes. Side by side, foliage at 1920x1080 inside 8-frame sequences at
# shader cost 0 and 64: deferred and DACS as they are, then DACS launched as one switch over
# power-of-two numbers of 4096-lane chunks (at most twice its lanes, one launch a level).
#   device run (carry .whl): bash benchmarks/gpu_twelfth_b.sh
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
T="python3 benchmarks/bench_time_work.py --frames 8 --scenes foliage --costs 0 64 --repeats 5"
timeout 90 $T --pipelines deferred dacs --label loop --out "$OUT/twelfth_b.jsonl" 2>&1 | quiet
JAXRENDER_DISPATCH=switch timeout 130 $T --pipelines dacs:chunk=4096 --label switch \
  --out "$OUT/twelfth_b.jsonl" 2>&1 | quiet
