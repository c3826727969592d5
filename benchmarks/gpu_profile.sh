#!/usr/bin/env bash
# Kernel profiles of the rasterizer and every pipeline on the lent GPU (one device call).
#   device run: bash benchmarks/gpu_profile.sh          (output: $OUT/profile.md)
#   one part:   bash benchmarks/gpu_profile.sh raster
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
LOG=$OUT/profile.md
T0=$(date +%s)
P() { echo "### +$(( $(date +%s) - T0 )) s: $*" | tee -a "$LOG"; timeout -k 5 ${STEP_S:-120} python3 benchmarks/profile_kernels.py "$@" 2>&1 | grep -v "^WARNING\|^I0000\|^E0000" | tee -a "$LOG"; }
TARGET="many_small:n_triangles=100000,point_lights=4"
PARTS=${*:-raster chunks pipelines flags}
for part in $PARTS; do case $part in
raster)
  P raster --resolution 1920x1080 --triangles 2600000 --top 20
  P raster --resolution 1920x1080 --triangles 2500 --top 12
  P raster --resolution 640x360 --triangles 10000 --top 12 ;;
chunks)
  for c in 4096 65536 262144; do P deferred --scene "$TARGET" --set chunk=$c --top 6; done ;;
pipelines)
  for p in forward visbuffer checkerboard dacs object_space; do P $p --scene "$TARGET" --top 12; done
  P reference --scene "$TARGET" --set k=4 --top 12 --calls 2 ;;
flags)
  XLA_FLAGS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE" P raster --resolution 640x360 --triangles 10000 --top 5
  XLA_FLAGS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE" P deferred --scene "$TARGET" --top 5 ;;
esac; done
echo "done in $(( $(date +%s) - T0 )) s" | tee -a "$LOG"
