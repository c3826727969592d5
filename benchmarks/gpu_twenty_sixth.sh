#!/usr/bin/env bash
# Prepared in the twenty-sixth session (carry [".whl", ".v"]; build .v first:
# benchmarks/variants/prepare.sh), one call:
#   bash benchmarks/gpu_twenty_sixth.sh glass profile checker      (about 3 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh visbuffer vbfits profile2  (about 3 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh dacs barrier                (about 3 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh launches crossover          (about 4 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh final                       (about 3 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh forward                     (about 4 minutes; ran)
#   bash benchmarks/gpu_twenty_sixth.sh profile3                    (about 1 minute; ran)
#   profile4: moved to gpu_twenty_seventh.sh, which ran it
# glass: v25 (3be237f: the transparent pass's depth test and its compaction in one prefix
#   launch, the layer shading in chunks of the compacted list into an array the size of the
#   whole fragment list, the composite in a second prefix launch) against this tree (the three
#   in one launch over the list's filled prefix, idle lanes for the fragments behind the opaque
#   depth), every pipeline that runs the pass, on glass. Counted on the CPU: 5 host reads a
#   frame fewer. Prediction: 0.25-0.4 ms a frame faster (the 8.3M-entry values array's
#   broadcast and scatters, 0.19 ms, and the reads), the layer shader itself about 15% longer
#   (1.55M lanes against 1.31M).
# profile: deferred on glass, this tree, kernels by scope.
# checker: prepared last session: checkerboard's half-screen list launched in one dense pass
#   (.v/dense_checker, one host read) against this tree's chunked dispatch (5 reads on
#   foliage). Prediction: dense 0.1-0.2 ms faster on foliage and room, equal on glass.
# visbuffer: the visibility buffer's wave-ordered work list shaded in one tiered launch
#   (dispatch.run_tiered over SCREEN_TIERS, one host read) against the chunked dispatch it
#   had (this tree under JAXRENDER_DISPATCH=blocks: on an opaque scene, the old program; 8
#   reads a frame on glass), on five opaque scenes; glass with this tree alone. Prediction:
#   as deferred's passes did in the nineteenth session, 5-12% faster on room and foliage, about
#   equal on terrain (62% covered: the half-screen tier misses, every lane runs).
# vbfits: the visibility buffer and deferred on foliage at shader costs 0 and 256. The
#   visibility buffer's slope was 0.72x deferred's with exact chunks (786k lanes); now it
#   launches deferred's tier (1.04M lanes for 757k points). Prediction: the ratio moves
#   towards 1 if a slope follows lanes; it stays if it follows points (as tiers_fine said).
# profile2: DACS and object space on glass (3.73 and 4.88 ms), kernels by scope.
# dacs: DACS's levels' loop in steps sized to a piece of the largest level, not to the whole of
#   it: .v/dacs_steps1 (one step a level, each padded to the largest: 5.2M entries decided a
#   frame at 1080p), this tree (2 pieces: six steps, 3.1M) and .v/dacs_steps4 (nine steps,
#   2.3M). profile2 gave decide 0.41 and interpolate 0.25 ms on glass. Prediction: this tree
#   0.2 ms a frame faster than steps1 on every scene; steps4 between (fewer entries, four more
#   steps of launches).
# barrier: the layer values materialized before the composite (.v/layer_barrier) against this
#   tree, where XLA fuses the tail of the layer shader into the sort's payload gather (0.14
#   ms). Prediction: 0.05-0.1 ms faster on glass.
# launches: does a shader's time per point follow its launch's size? The visibility buffer's
#   slope rose to deferred's when it launched deferred's tiers (1.04M lanes at once, not its
#   524k-lane blocks). A guess: a large launch's intermediates between the shader's fusions
#   spill out of the 50 MB L2 cache. Deferred and the visibility buffer on foliage, costs 0
#   and 256, at the auto chunk and chunks 131072 and 32768 (blocks of 4 chunks a launch).
#   Prediction if the guess holds: slopes fall with the launch size, below deferred's
#   0.0127 ms/M at chunk 32768, and the cost-0 times rise with the reads.
# crossover: deferred, checkerboard and DACS on foliage at costs 64 and 256 after DACS's steps
#   (last session: DACS's line crossed deferred's at about 31 layers).
# final: DACS (its steps) on every built-in scene; glass's pipelines whose transparent pass
#   changed, in one run; deferred, checkerboard and DACS on foliage at cost 0 (the crossover's
#   third point).
# forward: forward's shading list (its capacity the 8.3M-entry fragment list) takes the
#   largest auto chunk, 2^18, so it launches blocks of 1.05M lanes: the size at which deferred
#   paid 35% more per point (launches, above). Forward at the auto chunk against chunks 131072
#   and 65536 (blocks of 524k and 262k lanes): room and glass at their default shaders,
#   foliage at costs 0 and 256. Prediction: at 131072 forward's shading 20-25% cheaper per
#   point (room: 0.2-0.35 ms a frame less, its shading being 1.47 ms), less a few host reads.
# profile3: at the default shader checkerboard (1.78 ms) and DACS (2.26) are slower than
#   deferred (1.61) on foliage, though they shade a half and a ninth of its points: where
#   their frames go, kernels by scope, beside deferred's.
# profile4: profile3 again as 8-frame sequences of a still camera (history carried), where
#   checkerboard is slower than deferred: is the difference its temporal reconstruction?
. "$(dirname "$0")/gpu_env.sh"
S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
for part in "$@"; do
  if [ "$part" = glass ]; then
    side_by_side glass 150 "v25 after" --scenes glass \
      --pipelines deferred checkerboard dacs visbuffer
  elif [ "$part" = profile ]; then
    prof deferred glass 90 visibility gbuffer lighting transparent fragments layer_shading \
      composite sorted_blend
  elif [ "$part" = visbuffer ]; then
    side_by_side visbuffer 150 after --scenes foliage room terrain thin stripes glass \
      --pipelines visbuffer
    JAXRENDER_DISPATCH=blocks side_by_side visbuffer_blocks 150 after --scenes foliage room \
      terrain thin stripes --pipelines visbuffer
  elif [ "$part" = vbfits ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines visbuffer deferred --costs 0 256 --frames 8 --repeats 5 \
      --budget 130 --out "$OUT/vbfits.jsonl" 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/vbfits.md"
  elif [ "$part" = profile2 ]; then
    prof dacs glass 80 visibility dacs decide interpolate shade transparent layer_shading \
      composite
    prof object_space glass 80 visibility mark_allocate shade resolve counts reuse \
      transparent_marking transparent_resolve
  elif [ "$part" = dacs ]; then
    side_by_side dacs 200 "dacs_steps1 after dacs_steps4" --scenes foliage room glass \
      --pipelines dacs
  elif [ "$part" = barrier ]; then
    side_by_side barrier 120 "layer_barrier after" --scenes glass --pipelines deferred \
      checkerboard
  elif [ "$part" = launches ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines deferred deferred:chunk=131072 deferred:chunk=32768 \
      visbuffer visbuffer:chunk=32768 --costs 0 256 --frames 8 --repeats 5 --budget 180 \
      --out "$OUT/launches.jsonl" 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/launches.md"
  elif [ "$part" = crossover ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines deferred checkerboard dacs --costs 64 256 --frames 8 \
      --repeats 5 --budget 180 --out "$OUT/crossover.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/crossover.md"
  elif [ "$part" = final ]; then
    export PYTHONPATH=$PWD:/tmp/site
    timeout -k 5 320 $S --scenes stripes spheres foliage thin terrain sliver room many_small \
      foliage_wind spheres_spin grass glass --pipelines dacs --json "$OUT/final_dacs.json" \
      2>&1 | quiet | grep '^|' | tee -a "$OUT/final.md"
    timeout -k 5 120 $S --scenes glass --pipelines deferred checkerboard visbuffer \
      --json "$OUT/final_glass.json" 2>&1 | quiet | grep '^|' | tee -a "$OUT/final.md"
    timeout -k 5 90 python3 benchmarks/bench_time_work.py --scenes foliage \
      --pipelines deferred checkerboard dacs --costs 0 --frames 8 --repeats 5 \
      --out "$OUT/cost0.jsonl" 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/final.md"
  elif [ "$part" = forward ]; then
    export PYTHONPATH=$PWD:/tmp/site
    timeout -k 5 260 python3 benchmarks/bench_time_work.py --scenes room glass \
      --pipelines forward forward:chunk=131072 forward:chunk=65536 --costs 0 --frames 8 \
      --repeats 5 --budget 120 --out "$OUT/forward.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/forward.md"
    timeout -k 5 160 python3 benchmarks/bench_time_work.py --scenes foliage \
      --pipelines forward forward:chunk=131072 forward:chunk=65536 --costs 0 256 --frames 8 \
      --repeats 5 --budget 120 --out "$OUT/forward.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/forward.md"
  elif [ "$part" = profile3 ]; then
    prof deferred foliage 60 visibility gbuffer lighting
    prof checkerboard foliage 60 visibility plan shade spatial temporal counts
    prof dacs foliage 60 visibility dacs decide interpolate shade
  elif [ "$part" = checker ]; then
    side_by_side checker 80 "dense_checker after" --scenes foliage room glass \
      --pipelines checkerboard
  fi
done
exit 0
