#!/usr/bin/env bash
# Kernel profiles of the rasterizer and every pipeline on the lent GPU (one device call).
#   carry: [".whl"] (object_space needs xatlas)
#   device run: bash benchmarks/gpu_profile.sh          (output: $OUT/profile.md)
#   one part:   bash benchmarks/gpu_profile.sh raster
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "$0")/.."
if ls .whl/*.whl >/dev/null 2>&1; then  # carried wheels (xatlas for object_space and tads)
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl >/dev/null 2>&1 || echo "wheel install FAILED"
fi
export PYTHONPATH=$PWD:/tmp/site${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
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
issue23)  # the pipelines over their fixed-cost target, per named scope (issue 23)
  FW="--scope fragments --scope alpha_test --scope depth_test --scope quads --scope shade --scope resolve --scope counts"
  for sc in stripes foliage room; do P forward --scene $sc --top 14 $FW; done
  VB="--scope visibility --scope classify --scope shade --scope broadcast"
  for sc in thin room; do P visbuffer --scene $sc --top 12 $VB; done
  for sc in stripes grass room; do P dacs --scene $sc --top 12 --scope visibility --scope decide --scope interpolate --scope shade; done
  P deferred --scene room --top 8
  P object_space --scene thin --top 10
  P reference --scene room --top 12 --calls 2 --scope transform --scope raster --scope shade --scope reconstruct ;;
issue23b)  # tenth session: what is left over 3 ms, and inside the shader
  SH="--scope shade --scope texture --scope shadow_lookup --scope lights"
  FW="--scope fragments --scope alpha_test --scope depth_test --scope quads --scope resolve"
  for sc in thin room; do P forward --scene $sc --top 14 $FW $SH; done
  P visbuffer --scene room --top 12 --scope visibility --scope classify --scope broadcast $SH
  P object_space --scene thin --top 12 --scope visibility --scope mark_allocate --scope resolve $SH
  P deferred --scene glass --top 12 --scope visibility --scope transparent --scope sorted_blend $SH
  P forward --scene glass --top 12 --scope fragments --scope transparent --scope sorted_blend $SH
  P dacs --scene room --top 10 --scope visibility --scope decide --scope interpolate $SH
  P reference --scene room --top 14 --calls 2 --scope transform --scope raster --scope reconstruct $SH ;;
flags)
  XLA_FLAGS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE" P raster --resolution 640x360 --triangles 10000 --top 5
  XLA_FLAGS="--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE" P deferred --scene "$TARGET" --top 5 ;;
esac; done
echo "done in $(( $(date +%s) - T0 )) s" | tee -a "$LOG"
