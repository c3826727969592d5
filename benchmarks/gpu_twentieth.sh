#!/usr/bin/env bash
# Twentieth session's device calls (2026-12-05, H200 if one comes). carry [".whl"]:
#   bash benchmarks/gpu_twentieth.sh profile fits   (about 7 minutes)
#   bash benchmarks/gpu_twentieth.sh layers         (about 8 minutes)
#   bash benchmarks/gpu_every_scene.sh              (about 8 minutes)
# profile: where forward on room (the largest time above the visibility pass), DACS on
#   foliage and object space on thin (both above 1 ms over visibility everywhere, object space
#   above 3 ms on thin) spend their kernels, by named scope.
# fits: fixed cost and slope of every pipeline on foliage at shader costs 0 and 256
#   (benchmarks/gpu_fits.sh).
# layers: the shader-cost layers' picoseconds per layer evaluation at three launch sizes
#   (bench_cost_layers.py), then the fits on foliage, in this tree and in .v/layer_groups (the
#   layers summed eight at a time). As run on 2026-12-05 the groups were an in-tree knob
#   (groups 1, 4, 8, 16; RESULTS.md); the variant patch holds the same code. The first
#   call's fits (H100) gave slopes from 0.0047 (DACS, 4096-lane launches) to 0.0222 ms/M
#   (object space) around deferred's 0.0102; prediction: one at a time, the ps per evaluation
#   falls as the launch shrinks into the cache; grouped, it is flat across launch sizes and
#   the slopes converge. (Neither held: RESULTS.md.)
# os: object space against v19 (424a5fe), alternated twice, on thin, foliage, stripes and
#   room: its unowned-tap count now reads the store slots' owned bits instead of gathering the
#   sheet's owner map (150 M entries on thin). Prediction: 0.15-0.25 ms a frame less on thin
#   (the first call's profile: 0.24 ms in one resolve kernel), less elsewhere; then object
#   space on thin and deferred on room profiled (every kernel over 20 us).
# os2, os3: the same with the owned bits stored once, and the shading chunk from a quarter
#   screen. None of the three was adopted (RESULTS.md): "after" in these parts is now this
#   checkout without them, so rerunning them compares v19 with today's code.
. "$(dirname "$0")/gpu_env.sh"
prof() {  # prof PIPELINE SCENE SCOPE...
  local p=$1 s=$2
  shift 2
  PYTHONPATH=$PWD:/tmp/site timeout -k 5 100 python3 benchmarks/profile_kernels.py "$p" \
    --scene "$s" --top ${TOP:-14} --calls 3 $(printf -- '--scope %s ' "$@") 2>&1 | quiet \
    | tee -a "$OUT/profile.md"
}
for part in "$@"; do
  if [ "$part" = profile ]; then
    prof forward room visibility fragments alpha_test depth_test quads shade resolve counts
    prof dacs foliage visibility dacs decide interpolate shade reconstruct spatial temporal
    prof object_space thin visibility mark_allocate reuse shade resolve counts
  elif [ "$part" = layers ]; then  # build .v first: benchmarks/variants/prepare.sh
    for t in after layer_groups; do
      R=$PWD; [ $t = after ] || R=$PWD/.v/$t
      PYTHONPATH=$R:/tmp/site timeout -k 5 100 python3 benchmarks/bench_cost_layers.py \
        --scenes foliage room --sizes 4096 65536 0 --label $t --out "$OUT/cost_layers.jsonl" \
        2>&1 | quiet | tee -a "$OUT/cost_layers.md"
      PYTHONPATH=$R:/tmp/site timeout -k 5 170 python3 benchmarks/bench_time_work.py \
        --scenes foliage --frames 8 --costs 0 256 --repeats 5 --budget 150 --label $t \
        --out "$OUT/time_work.jsonl" --outputs all --pipelines visibility deferred checkerboard dacs forward \
        visbuffer tads object_space 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/fits.md"
    done
  elif [ "$part" = os ]; then
    for round in 1 2; do
      trees os.jsonl 120 "v19 after" --frames 16 --rounds 5 --scenes thin foliage stripes room \
        --pipelines object_space
    done
    TOP=30 prof object_space thin visibility mark_allocate reuse shade resolve counts
    TOP=20 prof deferred room visibility gbuffer lighting
  elif [ "$part" = os2 ]; then  # after the first os call: owned_slot stored once (int8)
    for round in 1 2; do
      trees os2.jsonl 120 "v19 after" --frames 16 --rounds 5 --scenes thin foliage stripes \
        room --pipelines object_space
    done
    TOP=12 prof object_space thin visibility mark_allocate reuse shade resolve counts
  elif [ "$part" = os3 ]; then  # object space's chunk from a quarter screen, not its store
    trees os3.jsonl 100 "v19 after" --frames 16 --rounds 5 --scenes foliage room \
      --pipelines object_space
  elif [ "$part" = fits ]; then
    FITS_S=${FITS_S:-200} BUDGET_S=${BUDGET_S:-170} bash benchmarks/gpu_fits.sh
  fi
done
exit 0
