#!/usr/bin/env bash
# Builds the trees that benchmarks/gpu_thirteenth.sh times side by side: .v/v0 (the code before
# the thirteenth session, 9a6cd99) and one .v/<name> per patch here (HEAD's jaxrender/ with the
# patch applied). Run from anywhere; .v/ is rebuilt from scratch.
set -euo pipefail
cd "$(dirname "$0")/../.."
rm -rf .v && mkdir -p .v/v0
git archive 9a6cd99 jaxrender | tar -x -C .v/v0
for p in benchmarks/variants/*.patch; do
  name=$(basename "$p" .patch)
  mkdir -p ".v/$name"
  git archive HEAD jaxrender | tar -x -C ".v/$name"
  patch -s -d ".v/$name" -p1 < "$p"
done
ls .v
