#!/usr/bin/env bash
# Prepared in the twenty-seventh session (carry [".whl"]), one call:
#   bash benchmarks/gpu_twenty_seventh.sh hlo profile4 shader refprof   (about 5 minutes; ran)
#   bash benchmarks/gpu_twenty_seventh.sh final   (right after, on the warm machine; ran)
#   bash benchmarks/gpu_twenty_seventh.sh texel   (carry .v: .v/soa1 and .v/full; ran)
#   bash benchmarks/gpu_twenty_seventh.sh fits    (not run: too little device time was left)
#   bash benchmarks/gpu_twenty_seventh.sh scenes1 / scenes2 / planhlo   (prepared, not run)
#   bash benchmarks/gpu_twenty_seventh.sh soa  (ran; planhlo not run)  (carry .v too: .v/v26 is 71adbb1's jaxrender)
# hlo: room's, foliage's and glass's shader in one launch over their covered pixels, each
#   effect off in turn (bench_shade_parts.py), the optimized programs kept (hlo.tar.gz): which
#   intermediates the 26 kernels of room's shader store (443 bytes a point, about 0.5 ms of its
#   1.2 at the H100's bandwidth, an estimate from sizes).
# profile4: checkerboard and deferred on foliage as 8-frame sequences of a still camera
#   (history carried): checkerboard is faster than deferred as one frame (1.80 against 2.16 ms
#   a call) and slower in an 8-frame pan (1.78 against 1.61). Is it the temporal pass?
# shader: deferred on room, the lighting pass's kernels (its shader in a pipeline).
# refprof: the 64-sample reference on room (93 ms on an H100), kernels by scope: how much is
#   its shading (64 x room's shader: about 77 ms at the rate above) and how much its passes.
# texel: the normal map on components (.v/full, the soa call's "after") made the reference on
#   room slower than the lights alone (.v/soa1): 89.2 against 74.6 ms, one 33.8 ms kernel, the
#   texture filtering 4.4 ms against 1.3: each of the normal map's four stored values filtered
#   the normal map again. This tree stores the texel first. Prediction: the reference at or
#   below soa1's 74.6 ms; room's one launch and deferred as full's (0.785 and 1.558 ms).
# final: this tree's pipelines on room, glass and foliage (8-frame pans, images only): glass's
#   six rows and forward on room were the seven over 3 ms.
# fits: foliage at costs 0 and 256 after the change (the layers now fuse: on a CPU foliage's
#   store 4 bytes a layer-lane, not 20). Slopes against deferred's were DACS 0.97x,
#   checkerboard 0.77x, the visibility buffer 0.74x.
# scenes1, scenes2: the nine other built-in scenes, every real-time pipeline, after the change
#   (the README's opaque column is from before it). About 5 minutes each.
# planhlo: checkerboard's optimized programs on foliage (8-frame sequence), for its plan's
#   0.13 ms kernel (input_add_and_compare_reduce_select_fusion, profile4).
# soa: the shader's lights and its last stage on per-point components (vec.components: tuples
#   of float32[N], not [N, 3] arrays), against v26. On [N, 3] each colour channel's kernel
#   recomputed the per-point terms shared by the three channels, so XLA stored them: room's
#   shader wrote 443 bytes a point between 26 kernels. Prediction: room's one launch 1.18 ->
#   0.6-0.8 ms, fewer kernels; deferred and forward on room 0.3-0.5 ms faster; the reference
#   on room (94.5 ms, 72 of them shading) 20-35 ms faster. Three trees: v26, soa1 (the lights
#   on components) and this tree (the surface points too: the reference's and forward's
#   shading computes them; deferred's G-buffer pass does) and the normal map.
. "$(dirname "$0")/gpu_env.sh"
S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
for part in "$@"; do
  if [ "$part" = hlo ]; then
    mkdir -p /tmp/hlo
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 python3 benchmarks/bench_shade_parts.py \
      --scenes room foliage glass --hlo /tmp/hlo --out "$OUT/shade_parts.jsonl" 2>&1 | quiet \
      | tee -a "$OUT/shade_parts.md"
    tar -czf "$OUT/hlo.tar.gz" -C /tmp hlo
  elif [ "$part" = soa ]; then
    for t in v26 soa1 after; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 90 python3 benchmarks/bench_shade_parts.py \
        --scenes room foliage glass spheres --own-effects --label $t \
        --out "$OUT/soa_parts.jsonl" 2>&1 | quiet | tee -a "$OUT/soa.md"
    done
    side_by_side soa_seq 130 "v26 soa1 after" --scenes room glass --pipelines deferred \
      forward
    S="python3 benchmarks/bench_sequence.py --frames 2 --rounds 3 --no-single --outputs images"
    side_by_side soa_ref 100 "v26 soa1 after" --scenes room --pipelines reference
  elif [ "$part" = final ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 400 $S --scenes room glass foliage --pipelines \
      deferred forward checkerboard dacs visbuffer object_space tads --json "$OUT/final.json" \
      2>&1 | quiet | grep '^|' | tee -a "$OUT/final.md"
  elif [ "$part" = texel ]; then
    for t in soa1 full after; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 60 python3 benchmarks/bench_shade_parts.py \
        --scenes room --own-effects --label $t --out "$OUT/texel_parts.jsonl" 2>&1 | quiet \
        | tee -a "$OUT/texel.md"
    done
    side_by_side texel_seq 60 "soa1 full after" --scenes room --pipelines deferred forward
    S="python3 benchmarks/bench_sequence.py --frames 2 --rounds 3 --no-single --outputs images"
    side_by_side texel_ref 60 "soa1 full after" --scenes room --pipelines reference
  elif [ "$part" = fits ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines deferred checkerboard dacs visbuffer --costs 0 256 \
      --frames 8 --repeats 5 --budget 170 --out "$OUT/fits.jsonl" 2>&1 | quiet \
      | grep -v '^{' | tee -a "$OUT/fits.md"
  elif [ "$part" = scenes1 ] || [ "$part" = scenes2 ]; then
    if [ "$part" = scenes1 ]; then SC="stripes spheres thin terrain sliver"
    else SC="many_small foliage_wind spheres_spin grass"; fi
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 400 $S --scenes $SC --pipelines deferred forward \
      checkerboard dacs visbuffer object_space tads --json "$OUT/$part.json" 2>&1 | quiet \
      | grep '^|' | tee -a "$OUT/$part.md"
  elif [ "$part" = planhlo ]; then
    XLA_FLAGS="--xla_dump_to=/tmp/dump --xla_dump_hlo_as_text" PYTHONPATH=$PWD:/tmp/site \
      timeout -k 5 90 python3 benchmarks/profile_kernels.py checkerboard --scene foliage \
      --top 8 --calls 1 --frames 8 2>&1 | quiet | tee -a "$OUT/planhlo.md"
    (cd /tmp/dump && ls -S | head -20 >> "$OUT/planhlo.md"; \
      tar -czf "$OUT/dump.tar.gz" $(ls | grep after_optimizations.txt))
  elif [ "$part" = profile4 ]; then
    for pipe in deferred checkerboard; do
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 70 python3 benchmarks/profile_kernels.py $pipe \
        --scene foliage --top 12 --calls 3 --frames 8 --scope visibility --scope gbuffer \
        --scope lighting --scope plan --scope shade --scope spatial --scope temporal 2>&1 \
        | quiet | tee -a "$OUT/profile4.md"
    done
  elif [ "$part" = shader ]; then
    prof deferred room 60 visibility gbuffer lighting shade lights texture
  elif [ "$part" = refprof ]; then
    prof reference room 120 raster shade transparent reconstruct lights texture
  fi
done
exit 0
