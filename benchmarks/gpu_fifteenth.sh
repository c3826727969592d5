#!/usr/bin/env bash
# Fifteenth session, one device call per line below (carry .whl and .v; build .v with
# benchmarks/variants/prepare.sh first):
#   bash benchmarks/gpu_fifteenth.sh profile reference
#   bash benchmarks/gpu_fifteenth.sh glass msaa
# profile: kernel profiles of what is still over issue 23's 3 ms (room's deferred and forward,
#   thin's forward, glass's deferred), named scopes summed, device copies named; output
#   $OUT/profile.md; and foliage's reference, where passes of 8 gained 4%.
# reference: the 64-sample reference inside a 2-frame pan (median of 3) for this checkout
#   ("after": the alpha test of the covered samples only, compacted) against v14 (07b2d0c),
#   and with its shading compacted into launches of half a pass (chunk = 8 x 1920 x 1080 / 2)
#   against in place. --checksum: image sums and invocations must agree.
# glass: every pipeline on glass (16-frame pan), deferred and forward with larger shading
#   chunks (the transparent pass's dispatch runs ~16 chunks of 2^18 lanes a screen, each a
#   loop iteration that reads its condition back) and with JAXRENDER_DISPATCH=switch, and
#   the blend_loop tree (the blending pass's layers in a loop again).
# msaa: as in gpu_fourteenth.sh (deferred with and without MSAA, after against v13).
. "$(dirname "$0")/gpu_env.sh"
P() { echo "### $*" >> "$OUT/profile.md"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 ${STEP_S:-75} python3 benchmarks/profile_kernels.py "$@" \
        2>&1 | quiet >> "$OUT/profile.md"; }
for part in "$@"; do
  if [ "$part" = profile ]; then
    SH="--scope shade --scope shadow_pass --scope shadow_lookup --scope lights --scope texture"
    P deferred --scene room --top 14 --calls 3 --scope visibility --scope gbuffer --scope resolve $SH
    P forward --scene room --top 14 --calls 3 --scope fragments --scope depth_test --scope quads \
      --scope resolve --scope counts $SH
    P forward --scene thin --top 12 --calls 3 --scope fragments --scope depth_test --scope quads \
      --scope resolve --scope counts --scope shade
    P deferred --scene glass --top 16 --calls 3 --copies --scope visibility --scope transparent \
      --scope sorted_blend --scope shade --scope fragments
    P reference --scene foliage --top 14 --calls 2 --scope raster --scope alpha \
      --scope surface_points --scope texture --scope shade --scope reconstruct
    grep -h "^## \|^scope" "$OUT/profile.md"
  elif [ "$part" = reference ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080"
    R="--frames 2 --rounds 3 --pipelines reference reference:chunk=8294400"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 240 $S $R --scenes foliage stripes room 2>&1 | quiet \
      | grep '^{' | sed 's/^{/{"tree": "after", /' | tee -a "$OUT/reference.jsonl"
    PYTHONPATH=$PWD/.v/v14:/tmp/site timeout -k 5 100 $S --frames 2 --rounds 3 --scenes foliage \
      --pipelines reference 2>&1 | quiet | grep '^{' | sed 's/^{/{"tree": "v14", /' \
      | tee -a "$OUT/reference.jsonl"
  elif [ "$part" = glass ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080"
    G="--frames 16 --rounds 5 --scenes glass"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 $S $G --pipelines forward deferred visbuffer \
      checkerboard dacs object_space deferred:chunk=1048576 deferred:chunk=4194304 \
      forward:chunk=1048576 2>&1 | quiet | grep '^{' | sed 's/^{/{"tree": "after", /' \
      | tee -a "$OUT/glass.jsonl"
    JAXRENDER_DISPATCH=switch PYTHONPATH=$PWD:/tmp/site timeout -k 5 80 $S $G \
      --pipelines deferred forward 2>&1 | quiet | grep '^{' \
      | sed 's/^{/{"tree": "after_switch", /' | tee -a "$OUT/glass.jsonl"
    PYTHONPATH=$PWD/.v/blend_loop:/tmp/site timeout -k 5 80 $S $G --pipelines deferred forward \
      2>&1 | quiet | grep '^{' | sed 's/^{/{"tree": "blend_loop", /' | tee -a "$OUT/glass.jsonl"
  elif [ "$part" = msaa ]; then
    bash benchmarks/gpu_fourteenth.sh msaa
  fi
done
exit 0
