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
# layfits (carry .v/base: `git archive f74db23 jaxrender`, the tree before the shader-cost
#   layers were summed in one reduction of their per-light terms, each layer's normal scaled
#   by a constant rather than normalized per point): foliage, costs 0 and 256, base, this
#   tree, then this tree with the graphs. In the
#   offline H100 program every shading launch at cost 256 stored a [257, lanes] array of each
#   layer's cosine and read it in two kernels (and six column copies); now the layers are
#   summed inside one reduction (DACS's launches at cost 256: 1,138 -> 916). Predicted:
#   deferred's slope 3-10x lower; DACS's fixed cost unchanged, its slope closer to deferred's
#   per lane (its 80 extra launches at cost 256 fall to about 15).
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
  elif [ "$part" = layfits ]; then
    for cfg in ${LAY_CFGS:-base after after_graphs}; do
      flags=""
      [ "$cfg" = after_graphs ] && flags="--xla_gpu_enable_command_buffer=$G"
      R=$(tree_root "${cfg%_graphs}") || continue
      XLA_FLAGS="$flags" PYTHONPATH=$R:/tmp/site timeout -k 5 170 python3 \
        benchmarks/bench_time_work.py --scenes foliage --pipelines ${LAY_PIPES:-deferred dacs} \
        --costs 0 256 --frames 8 --repeats 3 --budget 160 --label "$cfg" \
        --out "$OUT/layfits.jsonl" 2>&1 | quiet | grep -v '^{' | sed "s/^/$cfg: /" \
        | tee -a "$OUT/layfits.md"
    done
  elif [ "$part" = targets ] || [ "$part" = ten1 ] || [ "$part" = ten2 ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_eighth.sh "$part"
  else
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_ninth.sh "$part"
  fi
  bundle_out
done
exit 0
