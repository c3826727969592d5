#!/usr/bin/env bash
# Fortieth session. Call 1 (carry [".whl", ".v/pre39"]; .v/pre39 is `git archive 07ab04a
# jaxrender`, the tree before the thirty-ninth session's two untimed changes):
#   bash benchmarks/gpu_fortieth.sh gfits graphs untimed
# gfits: DACS's and deferred's fits on foliage (costs 0 and 256, 8-frame pans) with XLA's
#   default command buffers and with loops and branches in CUDA graphs (XLA_FLAGS), default
#   then graphs. In the thirty-fifth session DACS's wall grew 0.93 ms from cost 0 to 256 and
#   its kernels only 0.34: 80 more launches, and the time between them, made its slope 2.63x
#   deferred's. Predicted with graphs: DACS's slope 1.6-2.2x deferred's, its fixed cost
#   0.1-0.3 ms lower; deferred within 5%.
# graphs, untimed: as gpu_thirty_ninth.sh's (the other five real-time pipelines on glass with
#   and without the graphs; object space on glass and deferred on room, pre39 against this tree).
. "$(dirname "$0")/gpu_env.sh"
G=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE
for part in $(targets_first "$*"); do
  if [ "$part" = gfits ]; then
    for cfg in default graphs; do
      flags=""
      [ "$cfg" = graphs ] && flags="--xla_gpu_enable_command_buffer=$G"
      XLA_FLAGS="$flags" time_work "gfits_$cfg" 130 --scenes foliage \
        --pipelines ${GFITS_PIPES:-visibility deferred dacs} --costs 0 256 --frames 8 \
        --repeats 5 --budget 115 --label "$cfg"
    done
  elif [ "$part" = targets ] || [ "$part" = ten1 ] || [ "$part" = ten2 ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_eighth.sh "$part"
  else
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_ninth.sh "$part"
  fi
  bundle_out
done
exit 0
