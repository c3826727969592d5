#!/usr/bin/env bash
# Thirteenth session's plan (no machine was lent that session): the shader with its short
# reductions written as adds and stores between its stages (jaxrender/fusion.py), against the
# tree before it and against variants, side by side in one device call.
#   prepare: bash benchmarks/variants/prepare.sh (.v/v0 = 9a6cd99, .v/<name> = HEAD + <name>.patch)
#   device runs (carry .whl, .v):
#     bash benchmarks/gpu_thirteenth.sh shader sequence
#     TREES="after v0" PIPELINES="object_space tads" bash benchmarks/gpu_thirteenth.sh sequence
#     TREES="after dacs_adds" PIPELINES=dacs SEQ_SCENES="foliage room thin stripes" \
#       bash benchmarks/gpu_thirteenth.sh sequence
# The trees of that session: v0 = 9a6cd99 (before); v1 = this shader without its stores and
# v5 = without the surface point's store (both measured on an H200 on 2026-12-05, v5 adopted,
# their patches removed); h_store = with the half vector stored too;
# dacs_adds = DACS's per-level decision and interpolation with their short sums as adds
# (jaxrender/fusion.py; object space's footprint got the same rewrite in the tree itself).
# shader: bench_shader.py (one screen of surface_points + shade: kernels, launches) for this
#   checkout ("after") and each of SHADER_TREES (default "v0 h_store").
# sequence: per-frame ms inside a 16-frame pan with --checksum (equal counts, and image sums
#   within about 1e-5 relative, say the trees rendered the same frames; on the CPU they moved by
#   4e-6 at most) for each of TREES (default "after v0"); with the default
#   PIPELINES, the 64-sample reference inside a 2-frame pan too.
. "$(dirname "$0")/gpu_env.sh"
root_of() { if [ "$1" = after ]; then echo "$PWD"; else echo "$PWD/.v/$1"; fi; }
tag() { sed "s/^{/{\"tree\": \"$1\", /"; }
for part in "$@"; do
  if [ "$part" = shader ]; then
    for t in after ${SHADER_TREES:-v0 h_store}; do
      PYTHONPATH=$(root_of "$t"):/tmp/site timeout -k 5 150 python3 benchmarks/bench_shader.py \
        --label "$t" --top 6 --resolution ${RES:-1920x1080} --scenes ${SCENES:-room foliage stripes spheres terrain thin glass} \
        2>&1 | quiet >> "$OUT/shader.md"
    done
    grep RESULT "$OUT/shader.md"
  elif [ "$part" = sequence ]; then
    for t in ${TREES:-after v0}; do
      export PYTHONPATH=$(root_of "$t"):/tmp/site
      S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution ${RES:-1920x1080} --outputs all"
      timeout -k 5 200 $S --frames 16 --rounds 5 --scenes ${SEQ_SCENES:-room foliage spheres thin} \
        --pipelines ${PIPELINES:-forward deferred dacs visbuffer} 2>&1 | quiet | grep '^{' \
        | tag "$t" | tee -a "$OUT/sequence.jsonl"
      [ -n "${PIPELINES:-}" ] && continue
      timeout -k 5 120 $S --frames 2 --rounds 3 --scenes room foliage --pipelines reference \
        2>&1 | quiet | grep '^{' | tag "$t" | tee -a "$OUT/sequence.jsonl"
    done
  fi
done
exit 0
