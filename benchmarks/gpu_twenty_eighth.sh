#!/usr/bin/env bash
# Prepared in the twenty-eighth session (carry [".whl"]), one call each line:
#   bash benchmarks/gpu_twenty_eighth.sh glassprof fits planhlo
# glassprof: forward and object space on glass (5.13 and 4.55 ms, the two worst real-time rows
#   on an H100) and forward on room (3.06-3.11), kernels by scope: where their time goes after
#   the shader moved to per-point components.
# fits, planhlo: as in gpu_twenty_seventh.sh (prepared there, not run).
. "$(dirname "$0")/gpu_env.sh"
for part in "$@"; do
  if [ "$part" = glassprof ]; then
    prof forward glass 90 fragments alpha_test depth_test quads shade resolve counts \
      transparent lights texture
    prof object_space glass 90 mark_allocate reuse visibility shade resolve counts \
      transparent lights
    prof forward room 70 fragments alpha_test depth_test quads shade resolve counts lights \
      texture
  else
    OUT=$OUT bash benchmarks/gpu_twenty_seventh.sh "$part"
  fi
done
exit 0
