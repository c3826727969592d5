#!/usr/bin/env bash
# Fifteenth session, one device call per line below (carry .whl and .v; build .v with
# benchmarks/variants/prepare.sh first; v14 = 07b2d0c, the tree before this session):
#   bash benchmarks/gpu_fifteenth.sh forward reference profile     (ran 2026-12-05)
#   REF_TREES="after ref_chunks" REF_SCENES="foliage stripes room" bash ... reference   (ran)
#   bash benchmarks/gpu_fifteenth.sh chunks                        (ran)
#   bash benchmarks/gpu_fifteenth.sh glass                         (not run)
#   bash benchmarks/gpu_fifteenth.sh profile_b
# forward: forward (one sort: the draw list by quad, triangle, lane; no quad sort) and
#   deferred (unchanged, the control) on room, foliage, thin and terrain, 16-frame pans,
#   this checkout ("after") against v14, --checksum (image sums and invocations must agree).
#   Prediction: forward 0.3-0.5 ms a frame faster (the eleventh session's profile had two
#   radix sorts at 0.97 ms, forward's largest cost; one is gone), deferred unchanged.
# reference: the 64-sample reference inside a 2-frame pan (median of 3) for "after" against
#   v14 on REF_SCENES. The first call (2026-12-05) ran foliage and room with the alpha test
#   compacted, in place and with chunk = 8 x 1920 x 1080 / 2; "after" now launches each pass
#   once, compacted into half its lanes when at most half its samples are covered
#   (dispatch.shade_dense). Prediction: foliage about 34 ms (the chunked row), room as in place.
#   ref_chunks (measured 2026-12-05, not adopted, patch removed): traversal chunks of a
#   quarter of the default work capacity.
# profile: kernels of forward on room and of foliage's reference (after), named scopes summed.
# profile_b: deferred on room and on glass (copies named).
# glass: every pipeline on glass (16-frame pan), deferred and forward with larger shading
#   chunks (the transparent pass's dispatch runs ~16 chunks of 2^18 lanes a screen, each a
#   loop iteration that reads its condition back) and with JAXRENDER_DISPATCH=switch, and
#   with BLEND_LOOP=1 the blend_loop tree (the blending pass's layers in a loop again).
# chunks: deferred and forward on room and foliage with shading chunks of 2^20 against the
#   automatic 2^17-2^18 (a full screen is 8-16 loop iterations, each reading its condition
#   back; forward on room had 1.0 ms of device idle in a 4.3 ms span).
# msaa: as in gpu_fourteenth.sh (deferred with and without MSAA, after against v13).
. "$(dirname "$0")/gpu_env.sh"
P() { echo "### $*" >> "$OUT/profile.md"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 ${STEP_S:-75} python3 benchmarks/profile_kernels.py "$@" \
        2>&1 | quiet >> "$OUT/profile.md"; }
for part in "$@"; do
  if [ "$part" = profile ]; then
    P forward --scene room --top 14 --calls 3 --scope fragments --scope depth_test --scope quads \
      --scope shade --scope resolve --scope counts
    P reference --scene foliage --top 14 --calls 2 --scope raster --scope alpha \
      --scope surface_points --scope texture --scope shade --scope reconstruct
    grep -h "^## \|^scope" "$OUT/profile.md"
  elif [ "$part" = profile_b ]; then
    SH="--scope shade --scope shadow_pass --scope shadow_lookup --scope lights --scope texture"
    P deferred --scene room --top 14 --calls 3 --scope visibility --scope gbuffer --scope resolve $SH
    P deferred --scene glass --top 16 --calls 3 --copies --scope visibility --scope transparent \
      --scope sorted_blend --scope shade --scope fragments
    grep -h "^## \|^scope" "$OUT/profile.md"
  elif [ "$part" = forward ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --outputs all"
    F="--frames 16 --rounds 5 --scenes room foliage thin terrain --pipelines forward deferred"
    for t in after v14; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 150 $S $F 2>&1 | quiet | grep '^{' \
        | sed "s/^{/{\"tree\": \"$t\", /" | tee -a "$OUT/forward.jsonl"
    done
  elif [ "$part" = reference ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --outputs all"
    R="--frames 2 --rounds 3 --pipelines reference"
    for t in ${REF_TREES:-after ref_chunks v14}; do
      if [ $t = after ]; then T=$PWD; else T=$PWD/.v/$t; fi
      PYTHONPATH=$T:/tmp/site timeout -k 5 120 $S $R --scenes ${REF_SCENES:-stripes foliage room glass} \
        2>&1 | quiet | grep '^{' | sed "s/^{/{\"tree\": \"$t\", /" | tee -a "$OUT/reference.jsonl"
    done
  elif [ "$part" = glass ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --outputs all"
    G="--frames 16 --rounds 5 --scenes glass"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 $S $G --pipelines forward deferred visbuffer \
      checkerboard dacs object_space deferred:chunk=1048576 deferred:chunk=4194304 \
      forward:chunk=1048576 2>&1 | quiet | grep '^{' | sed 's/^{/{"tree": "after", /' \
      | tee -a "$OUT/glass.jsonl"
    JAXRENDER_DISPATCH=switch PYTHONPATH=$PWD:/tmp/site timeout -k 5 80 $S $G \
      --pipelines deferred forward 2>&1 | quiet | grep '^{' \
      | sed 's/^{/{"tree": "after_switch", /' | tee -a "$OUT/glass.jsonl"
    [ -n "${BLEND_LOOP:-}" ] && PYTHONPATH=$PWD/.v/blend_loop:/tmp/site timeout -k 5 80 $S $G \
      --pipelines deferred forward 2>&1 | quiet | grep '^{' \
      | sed 's/^{/{"tree": "blend_loop", /' | tee -a "$OUT/glass.jsonl"
  elif [ "$part" = chunks ]; then
    S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --outputs all"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 $S --frames 16 --rounds 5 --scenes room foliage \
      --pipelines deferred deferred:chunk=1048576 forward forward:chunk=1048576 2>&1 | quiet \
      | grep '^{' | sed 's/^{/{"tree": "after", /' | tee -a "$OUT/chunks.jsonl"
  elif [ "$part" = msaa ]; then
    bash benchmarks/gpu_fourteenth.sh msaa
  fi
done
exit 0
