#!/usr/bin/env bash
# Sixteenth session's device calls, prepared on a session with no machine lent (2026-12-05):
# build .v with benchmarks/variants/prepare.sh, carry [".whl", ".v"], one call per line:
#   bash benchmarks/gpu_sixteenth.sh modes_a        (room, thin)
#   bash benchmarks/gpu_sixteenth.sh modes_b        (foliage, glass, terrain)
#   bash benchmarks/gpu_sixteenth.sh forward reads
# modes_*: every pipeline but the reference in a 16-frame pan at 1920x1080 under each
#   dispatch launch mode (JAXRENDER_DISPATCH = loop, blocks, switch; DACS's levels follow the
#   variable too, so its "loop" row is not its default), --checksum, compile times in the rows.
#   Prediction from the host reads counted on the CPU (`python -m jaxrender.bench.round_trips`,
#   RESULTS.md, 2026-12-05 sixteenth session) at the fifteenth session's ~27 µs a read
#   (deferred on room: 30 reads fewer under switch, 0.82 ms a frame faster): blocks about
#   0.4 ms faster than the loop on deferred/room (36 -> 20 reads), 0.2 on visbuffer/room
#   (20 -> 12), 0.05-0.15 elsewhere, and never slower by more than noise on the rows where it
#   adds a read (foliage checkerboard 10 -> 12, object_space); switch as measured before.
#   Compile: blocks compiles the shader twice (two launch sizes), switch five or six times.
# forward: forward on room, foliage, thin, terrain and glass, this checkout ("after": its depth
#   test and alpha candidates run over the draw list's filled prefix, `sorting.on_prefix`)
#   against v15, with deferred (unchanged) as the control. Prediction: forward 0.1-0.3 ms
#   faster on room (26% of the fragment capacity filled) and foliage (13%), one read more.
# reads: deferred on glass profiled (its device-to-host copies counted by the profile), to
#   check the CPU count of 48 reads a frame at 1920x1080.
. "$(dirname "$0")/gpu_env.sh"
S="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --frames 16 --outputs all"
PIPES="forward deferred visbuffer checkerboard dacs object_space tads"
modes() {
  for m in loop blocks switch; do
    JAXRENDER_DISPATCH=$m PYTHONPATH=$PWD:/tmp/site timeout -k 5 170 $S --rounds 5 \
      --scenes "$@" --pipelines $PIPES 2>&1 | quiet | grep '^{' \
      | sed "s/^{/{\"mode\": \"$m\", /" | tee -a "$OUT/modes.jsonl"
  done
}
for part in "$@"; do
  if [ "$part" = modes_a ]; then
    modes room thin
  elif [ "$part" = modes_b ]; then
    modes foliage glass terrain
  elif [ "$part" = forward ]; then
    for t in after v15; do
      if [ $t = after ]; then R=$PWD; else R=$PWD/.v/$t; fi
      PYTHONPATH=$R:/tmp/site timeout -k 5 170 $S --rounds 5 --pipelines forward deferred \
        --scenes room foliage thin terrain glass 2>&1 | quiet | grep '^{' \
        | sed "s/^{/{\"tree\": \"$t\", /" | tee -a "$OUT/forward.jsonl"
    done
  elif [ "$part" = reads ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 120 python3 benchmarks/profile_kernels.py deferred \
      --scene glass --top 12 --calls 3 --copies 2>&1 | quiet | tee -a "$OUT/reads.md"
  fi
done
exit 0
