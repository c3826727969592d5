#!/usr/bin/env bash
# Eighteenth session's device calls (2026-12-05): build .v with benchmarks/variants/prepare.sh,
# carry [".whl", ".v"]:
#   bash benchmarks/gpu_eighteenth.sh dense os profile
# dense: deferred on five scenes, this checkout (blocks) against .v/dense_deferred (its G-buffer
#   and lighting passes through `dispatch.shade_dense` with tiers (8, 4, 2): one launch each,
#   the covered pixels compacted into an eighth, a quarter or half the screen's lanes, in place
#   above half; one host read each instead of blocks' n // 4 + n % 4 + 2, 8 on room) and
#   against this checkout under JAXRENDER_DISPATCH=switch (one read too, but compacted always
#   and five or six shader copies). Prediction: room 2.8 -> 2.3-2.4 ms (the switch's 2.38 last
#   session, 14 reads fewer), the other scenes as the switch did (foliage 1.71 -> 1.53, thin,
#   glass and terrain within 0.1 ms), compile as blocks' plus two shader copies.
#   The same for checkerboard (.v/dense_checker: its half-screen list in one launch, 1 read
#   instead of 4 on room): prediction 0.05-0.1 ms less.
# The nineteenth session adopted dense_deferred (gpu_nineteenth.sh times it against blocks),
# so dense now times checkerboard alone.
# Any other part goes to gpu_seventeenth.sh (os, glass, glass2, profile, reference).
. "$(dirname "$0")/gpu_env.sh"
rest=()
for part in "$@"; do
  if [ "$part" = dense ]; then
    trees dense_checker.jsonl 150 "after dense_checker" --frames 16 --rounds 5 \
      --scenes room foliage thin glass terrain --pipelines checkerboard
  else
    rest+=("$part")
  fi
done
[ ${#rest[@]} -eq 0 ] || bash benchmarks/gpu_seventeenth.sh "${rest[@]}"
exit 0
