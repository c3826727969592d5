#!/usr/bin/env bash
# Twelfth session: every pipeline inside a 16-frame pan at 1920x1080 with XLA's default command
# buffers, then with while loops and conditionals moved into them (CUDA graph conditional
# nodes: the scan over frames, the dispatch loops and the chunk loops keep their trip counts on
# the device). A sequence is one call, so the graph's per-call update is paid once per 16
# frames. --checksum shows both variants rendered the same frames.
#   device run (carry .whl): bash benchmarks/gpu_twelfth.sh
. "$(dirname "$0")/gpu_env.sh"
export PYTHONPATH=$PWD:/tmp/site
LOG=$OUT/twelfth.md
GRAPHS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE"
S="python3 benchmarks/bench_sequence.py --frames 16 --rounds 5 --no-single --checksum"
for variant in default graphs; do
  flags=${XLA_FLAGS:-}; [ $variant = graphs ] && flags="$flags $GRAPHS"
  echo "## $variant" | tee -a "$LOG"
  XLA_FLAGS="$flags" timeout ${LIMIT:-270} $S --scenes ${SCENES:-thin room foliage glass} 2>&1 \
    | quiet | grep '^{\|Error\|error' | tee -a "$LOG"
done
