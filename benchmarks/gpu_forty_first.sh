#!/usr/bin/env bash
# Forty-first session. Call 1 (carry [".whl", ".v/base"]; .v/base is `git archive f74db23
# jaxrender`, the tree before the fortieth session's shader-cost layers summed in one kernel):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_forty_first.sh laybase fitsall
# laybase: deferred and DACS on foliage at costs 0 and 256 in the base tree (8-frame pans), as
#   gpu_fortieth.sh's layfits. fitsall: every real-time pipeline and the visibility pass on
#   foliage at costs 0 and 256 in this tree: the fixed costs and slopes of issue 23 after the
#   layers were fused. Predicted (fortieth session, from the offline H100 programs): deferred's
#   slope 2-5x lower than base's; DACS's per-point slope nearer deferred's (its 80 extra
#   launches at cost 256 fall to about 15), the ratio perhaps not lower as deferred's falls
#   too; checkerboard's and DACS's crossovers against deferred rise.
# Call 2 (carry [".whl", ".v/pre39"]; .v/pre39 is `git archive 07ab04a jaxrender`), on an H200:
#   bash benchmarks/gpu_forty_first.sh refprof (targets first); on an H100:
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_forty_first.sh untimed refprof
# refprof: the 64-sample reference on terrain and foliage, kernels by scope (one frame a call):
#   where its 37-39 ms go (H100, twenty-seventh session) against issue 23's 25. The offline
#   H100 program streams about 4 GB a pass of 8 samples (32 GB, ~10 ms a frame at 3.35 TB/s),
#   so most of the frame is not its large buffers' traffic. untimed: as gpu_thirty_ninth.sh's.
# Prepared later in the session (no device came; carry [".whl", ".v/b41",
# ".v/barycentric_columns"]: .v/b41 is `git archive 46405b1 jaxrender`, the tree before this
# session's changes, and .v/barycentric_columns this tree with
# benchmarks/variants/barycentric_columns.patch applied, as benchmarks/variants/prepare.sh
# builds it):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_forty_first.sh cols refab
# cols: forward, deferred and object space on glass, this tree against the columns variant
#   (A B B A): the barycentrics as columns, which XLA stops storing (offline H100 programs:
#   forward 681 -> 600 launching instructions, its shading block of 2^20 lanes writes 50 MB
#   where it writes 130, the transparent layers' branches about half) but computes again in
#   every kernel that uses them (1.3-10x slower on the CPU, RESULTS.md). Predicted on a GPU:
#   forward on glass within -0.3..+0.2 ms a frame: the traffic it saves against the
#   recomputation, which the offline program cannot weigh.
# refab: the 64-sample reference on terrain, foliage and room (2-frame pans), b41, this tree
#   and the columns variant: this tree computes the samples' barycentrics where it shades and
#   no longer copies the depth buffer's fill (predicted 1-2% faster); the variant stores no
#   barycentrics (a pass writes 0.7-1.2 GB less than b41's, offline).
. "$(dirname "$0")/gpu_env.sh"
for part in $(targets_first "$*"); do
  if [ "$part" = laybase ]; then
    NO_AUTO_TARGETS=1 LAY_CFGS=base OUT=$OUT bash benchmarks/gpu_fortieth.sh layfits
  elif [ "$part" = fitsall ]; then
    time_work fitsall "${FITS_LIMIT:-400}" --scenes foliage --pipelines ${FITS_PIPES:-visibility \
      deferred dacs checkerboard visbuffer tads forward object_space} --costs 0 256 --frames 8 \
      --repeats 3 --budget "$(( ${FITS_LIMIT:-400} - 20 ))" --label after
  elif [ "$part" = cols ]; then
    cached_compiles
    S=$S8
    side_by_side cols 200 "after barycentric_columns" --scenes glass --pipelines forward \
      deferred object_space
  elif [ "$part" = refab ]; then
    cached_compiles
    S="python3 benchmarks/bench_sequence.py --frames 2 --rounds 3 --no-single --outputs images"
    ORDERS=1 side_by_side refab 200 "b41 after barycentric_columns" --scenes terrain foliage \
      room --pipelines reference
  elif [ "$part" = refprof ]; then
    prof reference terrain 150 raster shade resolve coverage reconstruct
    prof reference foliage 150 raster shade resolve coverage alpha reconstruct
  elif [ "$part" = targets ] || [ "$part" = ten1 ] || [ "$part" = ten2 ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_eighth.sh "$part"
  elif [ "$part" = untimed ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_ninth.sh untimed
  else
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_fortieth.sh "$part"
  fi
  bundle_out
done
exit 0
