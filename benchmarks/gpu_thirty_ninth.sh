#!/usr/bin/env bash
# Thirty-ninth session. Call 1 (carry [".whl", ".v/b39", ".v/taps1", ".v/rows34", ".v/fsw"]; .v/b39 is
# `git archive 149b213 jaxrender`, the others `git archive 61f08a5 jaxrender` with one patch of
# benchmarks/variants applied: taps1 taps_one_index, rows34 os_transparent_rows_three_quarters):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_thirty_ninth.sh clipjoin osparts graphs prof38
# clipjoin: forward and deferred on glass, this tree against b39 (A B B A): the first clip
#   chunk's fans joined to the coverage list (f40e951) take 3 host reads a frame out of each,
#   and forward's sort and replay in one branch (61f08a5) one more (CPU count: forward
#   15 -> 11, deferred 10 -> 7). Predicted 0.08-0.2 ms a frame faster (27-50 us a read,
#   fifteenth and sixteenth sessions).
# osparts: object space on glass, this tree against taps1 and rows34 (A B C C B A). The
#   thirty-eighth session timed them together with the once-a-pixel marking (osnew: 0.46 ms a
#   frame slower); the offline program blamed the marking. Predicted: taps1 0.03-0.1 ms faster
#   (8 bytes a tap stored and read twice, not 13: ~200 MB less traffic on glass), rows34
#   0.05-0.2 faster (3.63M joined rows, not 4.15M).
# graphs: forward and object space on glass with XLA's default command buffers and with loops
#   and conditionals in them too (--xla_gpu_enable_command_buffer=...,CONDITIONAL,WHILE: their
#   predicates stay on the device), A B B A. Last tried in the twelfth session (glass 0.93-0.99x,
#   DACS and the visibility buffer up to 1.22x); since then the frames hold far fewer kernels
#   (forward glass 6.56 -> 3.36 ms) and still test 14-16 predicates a frame (round_trips.py, CPU
#   count), about 50 us of idle device each (fifteenth session). Predicted 0.9-1.0x.
# fswitch (carry .v/fsw: this tree with benchmarks/variants/forward_shade_switch.patch):
#   forward on glass and room, this tree against fsw (A B B A): forward's opaque units
#   launched in one switch over power-of-two chunk counts, not in blocks (glass 8 chunks: 4
#   host reads -> 1, and since the thirty-seventh session's split its units fill the chunks:
#   glass about 2.0M units in 2,097,152 lanes, room 2,085,405). Predicted 0.05-0.15 ms a frame
#   faster on both; cold compile longer (six shader copies, not two).
# Call 1 ran on an H100 (RESULTS.md, thirty-ninth session); rows34 and graphs (for forward and
# object space) adopted. Call 2 (carry [".whl", ".v/fsw"], .v/fsw at 08c5d91 with the patch):
#   NO_AUTO_TARGETS=1 bash benchmarks/gpu_thirty_ninth.sh final39 fswitch
# final39: forward and object space on glass and room in this tree (8-frame pans, images
#   only): the rows over 3 ms before this session (H200: forward 3.36, object space 3.58 on
#   glass). Predicted on an H100: forward glass 3.45-3.55, object space glass 3.85-3.95.
# Call 3 (carry [".whl"]): NO_AUTO_TARGETS=1 bash benchmarks/gpu_thirty_ninth.sh osprof39
# osprof39: object space's 8-frame sequence on glass by scope (prof38's failed: the profiler
#   traced the sequence inside another jit, where the sheet cannot be built).
# prof38: as gpu_thirty_eighth.sh's (object space's and forward's 8-frame sequences on glass
#   by scope).
# All three calls ran on H100s (RESULTS.md, thirty-ninth session); no H200 came.
# Next session (carry [".whl", ".v/pre39"]; .v/pre39 is `git archive 07ab04a jaxrender`, the
# tree before the two untimed changes):
#   bash benchmarks/gpu_thirty_ninth.sh untimed graphs
# untimed: object space on glass and deferred on room, pre39 against this tree (A B B A): the
#   taps' chunk and lane by shifts and masks (cd951d1; predicted 0.05-0.2 ms a frame faster
#   for object space) and the texture's wrap without remainders (0a16079; predicted a few
#   percent of a textured scene's shading).
# graphs (GRAPH_PIPES; call 1 ran forward and object space, the default is the other five):
#   those pipelines with and without loops and branches in CUDA graphs (XLA_FLAGS; forward and
#   object space have them as a compile option now), to decide `DEVICE_CONTROL_FLOW` for them.
# ten1, ten2: as gpu_thirty_eighth.sh's (the ten other built-in scenes on an H200).
. "$(dirname "$0")/gpu_env.sh"
cached_compiles
S=$S8
for part in $(targets_first "$*"); do
  if [ "$part" = clipjoin ]; then
    side_by_side clipjoin 120 "b39 after" --scenes glass --pipelines forward deferred
  elif [ "$part" = osparts ]; then
    side_by_side osparts 110 "after taps1 rows34" --scenes glass --pipelines object_space
  elif [ "$part" = graphs ]; then
    G=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE
    for cfg in default graphs graphs default; do
      flags=""
      [ "$cfg" = graphs ] && flags="--xla_gpu_enable_command_buffer=$G"
      XLA_FLAGS="$flags" PYTHONPATH=$PWD:/tmp/site timeout -k 5 240 $S --scenes glass \
        --pipelines ${GRAPH_PIPES:-deferred checkerboard dacs visbuffer tads} 2>&1 | quiet \
        | tee -a "$OUT/graphs_$cfg.log" | grep '^|' | sed "s/^/$cfg: /" | tee -a "$OUT/graphs.md"
    done
  elif [ "$part" = untimed ]; then
    side_by_side untimed_os 150 "pre39 after" --scenes glass --pipelines object_space
    side_by_side untimed_room 150 "pre39 after" --scenes room --pipelines deferred
  elif [ "$part" = final39 ]; then
    nvidia-smi --query-gpu=name --format=csv,noheader | tee -a "$OUT/final39.md"
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 200 $S --scenes glass room --pipelines forward \
      object_space --json "$OUT/final39.json" 2>&1 | quiet | grep '^|' | tee -a "$OUT/final39.md"
  elif [ "$part" = osprof39 ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 140 python3 benchmarks/profile_kernels.py \
      object_space --scene glass --frames 8 --top 40 --calls 3 --scope-top 8 \
      $(printf -- '--scope %s ' mark_allocate reuse visibility shade resolve \
        transparent_marking transparent_resolve transparent sorted_blend) 2>&1 | quiet \
      | tee -a "$OUT/osprof39.md"
  elif [ "$part" = fswitch ]; then
    side_by_side fswitch 150 "after fsw" --scenes ${FSWITCH_SCENES:-glass room} --pipelines forward
  elif [ "$part" = prof38 ] || [ "$part" = ten1 ] || [ "$part" = ten2 ] \
    || [ "$part" = targets ]; then
    NO_AUTO_TARGETS=1 OUT=$OUT bash benchmarks/gpu_thirty_eighth.sh "$part"
  fi
  bundle_out
done
exit 0
