#!/usr/bin/env bash
# Seventeenth session's device calls (2026-12-05): build .v with benchmarks/variants/prepare.sh,
# carry [".whl", ".v"], one call per line:
#   bash benchmarks/gpu_sixteenth.sh modes_a        (loop / blocks / switch on room, thin)
#   bash benchmarks/gpu_sixteenth.sh modes_b        (foliage, glass, terrain)
#   bash benchmarks/gpu_seventeenth.sh glass profile
#   bash benchmarks/gpu_seventeenth.sh glass2 reference profile
#   bash benchmarks/gpu_seventeenth.sh os        (the device time left: object space alone)
# glass: every pipeline on glass, this checkout against v16 (fd3a891): the transparent pass's
#   front test, work list and composite now read the fragment list's filled prefix only
#   (`transparency.front_work`, `composite` through `sorting.on_prefix`); glass fills about 15%
#   of its 8.3M-entry list at 1920x1080. Prediction: 0.2-0.5 ms a frame less for deferred,
#   visbuffer, checkerboard, DACS and TADS on glass; object space less (its joined footprint
#   still spans the whole list). Forward on room and foliage against v15 too (the sixteenth
#   session's replay over the prefix), with deferred on room as the control.
# profile: object space, then deferred, on glass, kernel by kernel, by named scope; forward on
#   room.
# glass2 (after the first call, whose glass rows showed the composite on the prefix compiling
#   deferred 7 s longer): this checkout, .v/sort_prefix_only (the composite over the whole
#   list, its sort alone on the prefix, as in v16) and v16, all under JAXRENDER_DISPATCH=blocks
#   (this checkout's new default). Object space now compacts its transparent samples to one
#   per pixel (glass: about 0.6 in front per pixel): prediction 3-4 ms less on glass, about
#   the transparent_marking, mark_allocate and resolve time over the 8.3M-entry list.
# reference: the 64-sample reference on glass, 4 frames, this checkout against v16.
. "$(dirname "$0")/gpu_env.sh"
for part in "$@"; do
  if [ "$part" = glass ]; then
    trees glass.jsonl 200 "after v16" --frames 16 --rounds 5 --scenes glass \
      --pipelines forward deferred visbuffer checkerboard dacs object_space
    trees forward.jsonl 120 "after v15" --frames 16 --rounds 5 --scenes room foliage \
      --pipelines forward deferred
  elif [ "$part" = glass2 ]; then
    JAXRENDER_DISPATCH=blocks trees glass2.jsonl 150 "after sort_prefix_only v16" --frames 16 \
      --rounds 5 --scenes glass --pipelines deferred visbuffer dacs object_space
  elif [ "$part" = os ]; then
    JAXRENDER_DISPATCH=blocks trees os.jsonl 70 "after v16" --frames 8 --rounds 3 \
      --scenes glass --pipelines object_space
  elif [ "$part" = reference ]; then
    JAXRENDER_DISPATCH=blocks trees reference.jsonl 100 "after v16" --frames 4 --rounds 3 \
      --scenes glass --pipelines reference
  elif [ "$part" = profile ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py \
      object_space --scene glass --top 16 --calls 2 --scope visibility --scope transparent_marking \
      --scope mark_allocate --scope reuse --scope shade --scope resolve --scope transparent_resolve \
      --scope counts 2>&1 | quiet | tee -a "$OUT/profile.md"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py \
      deferred --scene glass --top 12 --calls 2 --scope visibility --scope gbuffer \
      --scope lighting --scope transparent --scope fragments --scope front \
      --scope layer_shading --scope composite --scope sorted_blend 2>&1 | quiet \
      | tee -a "$OUT/profile.md"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py \
      forward --scene room --top 12 --calls 2 --scope fragments --scope depth_test --scope quads \
      --scope shade --scope resolve --scope counts 2>&1 | quiet | tee -a "$OUT/profile.md"
  fi
done
exit 0
