#!/usr/bin/env bash
# Thirty-ninth session. Call 1 (carry [".whl", ".v/taps1", ".v/rows34"]; each .v tree is
# `git archive 149b213 jaxrender` with one patch of benchmarks/variants applied: taps1
# taps_one_index, rows34 os_transparent_rows_three_quarters):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_thirty_ninth.sh osparts prof38
# osparts: object space on glass, this tree against taps1 and rows34 (A B C C B A). The
#   thirty-eighth session timed them together with the once-a-pixel marking (osnew: 0.46 ms a
#   frame slower); the offline program blamed the marking. Predicted: taps1 0.03-0.1 ms faster
#   (8 bytes a tap stored and read twice, not 13: ~200 MB less traffic on glass), rows34
#   0.05-0.2 faster (3.63M joined rows, not 4.15M).
# prof38: as gpu_thirty_eighth.sh's (object space's and forward's 8-frame sequences on glass
#   by scope).
# ten1, ten2: as gpu_thirty_eighth.sh's (the ten other built-in scenes on an H200).
. "$(dirname "$0")/gpu_env.sh"
export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
  JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
for part in $(targets_first "$*"); do
  if [ "$part" = osparts ]; then
    side_by_side osparts 110 "after taps1 rows34" --scenes glass --pipelines object_space
  elif [ "$part" = prof38 ] || [ "$part" = ten1 ] || [ "$part" = ten2 ] \
    || [ "$part" = targets ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_eighth.sh "$part"
  fi
  bundle_out
done
exit 0
