#!/usr/bin/env bash
# Eighteenth session's device calls (2026-12-05): build .v with benchmarks/variants/prepare.sh,
# carry [".whl", ".v"]:
#   bash benchmarks/gpu_eighteenth.sh dense os profile
# dense: deferred on five scenes, this checkout against .v/dense_deferred (its G-buffer and
#   lighting passes through `dispatch.shade_dense`: one launch, in place above half coverage,
#   else compacted into half the screen's lanes; one host read each instead of blocks' n // 4 +
#   n % 4 + 2, 8 on room). Prediction: room 2.8 -> 2.4-2.5 ms (16 reads -> 2 at the ~27 us a
#   read of the switch-against-loop rows), less where the screen is sparse (lanes up to half
#   the screen), foliage and thin no better (the switch did not help them either).
# Any other part goes to gpu_seventeenth.sh (os, glass, glass2, profile, reference).
. "$(dirname "$0")/gpu_env.sh"
rest=()
for part in "$@"; do
  if [ "$part" = dense ]; then
    trees dense.jsonl 150 "after dense_deferred" --frames 16 --rounds 5 \
      --scenes room foliage thin glass terrain --pipelines deferred
  else
    rest+=("$part")
  fi
done
[ ${#rest[@]} -eq 0 ] || bash benchmarks/gpu_seventeenth.sh "${rest[@]}"
exit 0
