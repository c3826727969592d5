#!/usr/bin/env bash
# Fixed cost and XLA's command buffers, side by side in one device call: each pipeline's
# untraced wall time on foliage at 1920x1080 with XLA's default command buffers, and with
# while loops and conditionals moved into them (CUDA graph conditional nodes: a dispatch
# loop's trip count then stays on the device instead of a host round trip per chunk).
#   device run: bash benchmarks/gpu_command_buffers.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
BASE="${XLA_FLAGS:-}"
GRAPHS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE"
for p in ${PIPELINES:-deferred checkerboard dacs visbuffer object_space forward}; do
  for variant in default graphs; do
    flags=$BASE; [ $variant = graphs ] && flags="$BASE $GRAPHS"
    echo "### $p $variant"
    XLA_FLAGS="$flags" timeout 90 python3 benchmarks/profile_kernels.py $p --scene foliage \
      --top ${TOP:-6} --calls 5 2>&1 | quiet
  done
done | tee "$OUT/command_buffers.md" | grep "^##\|wall"
