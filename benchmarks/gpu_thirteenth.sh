#!/usr/bin/env bash
# Thirteenth session's plan (no machine was lent that session): the shader with its short
# reductions written as adds and stores between its stages (jaxrender/shading/fusion.py),
# against the tree before it, side by side in one device call.
#   prepare: mkdir -p .v/v0 && git archive 9a6cd99 jaxrender | tar -x -C .v/v0
#            (any other .v/<name>/jaxrender is timed too, in the shader part)
#   device run (carry .whl, .v): bash benchmarks/gpu_thirteenth.sh shader sequence
# shader: bench_shader.py (one screen of surface_points + shade, kernels and launches) per tree.
# sequence: per-frame ms inside a 16-frame pan, with --checksum (equal image sums and counts
# say both trees rendered the same frames); the 64-sample reference inside a 2-frame pan.
. "$(dirname "$0")/gpu_env.sh"
trees() { echo "after:$PWD"; for d in .v/*/; do echo "$(basename "$d"):$PWD/$d"; done; }
for part in "$@"; do
  for t in $(trees); do
    label=${t%%:*}; root=${t#*:}
    export PYTHONPATH=$root:/tmp/site
    if [ "$part" = shader ]; then
      timeout -k 5 150 python3 benchmarks/bench_shader.py --label "$label" --top 6 \
        --scenes ${SCENES:-room foliage stripes spheres terrain thin glass} 2>&1 | quiet \
        >> "$OUT/shader.md"
    elif [ "$part" = sequence ]; then
      [ "$label" = after ] || [ "$label" = v0 ] || continue
      S="python3 benchmarks/bench_sequence.py --no-single --checksum"
      timeout -k 5 200 $S --frames 16 --rounds 5 --scenes room foliage spheres thin \
        --pipelines forward deferred dacs visbuffer 2>&1 | quiet | grep '^{' \
        | sed "s/^{/{\"tree\": \"$label\", /" | tee -a "$OUT/sequence.jsonl"
      timeout -k 5 120 $S --frames 2 --rounds 3 --scenes room foliage \
        --pipelines reference 2>&1 | quiet | grep '^{' \
        | sed "s/^{/{\"tree\": \"$label\", /" | tee -a "$OUT/sequence.jsonl"
    fi
  done
done
[ -f "$OUT/shader.md" ] && grep RESULT "$OUT/shader.md"
exit 0
