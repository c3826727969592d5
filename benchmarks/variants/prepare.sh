#!/usr/bin/env bash
# Builds the trees that benchmarks/gpu_thirteenth.sh and gpu_fourteenth.sh time side by side:
# .v/v0 (the code before the thirteenth session, 9a6cd99), .v/v13 (before the fourteenth,
# c298392), .v/v14 (before the fifteenth, 07b2d0c), .v/v15 (before the sixteenth,
# 39e025f), .v/v16 (before the seventeenth, fd3a891), .v/v19 (before the twentieth,
# 424a5fe), .v/v20 (c87d91d), .v/v24 (before the twenty-fifth, 593a3ff), .v/v25 (before the twenty-sixth, 3be237f) and one .v/<name>
# per patch here (HEAD's jaxrender/ with the patch applied). Run from anywhere; .v/ is rebuilt from scratch.
set -euo pipefail
cd "$(dirname "$0")/../.."
rm -rf .v && mkdir -p .v/v0
git archive 9a6cd99 jaxrender | tar -x -C .v/v0
mkdir -p .v/v13
git archive c298392 jaxrender | tar -x -C .v/v13
mkdir -p .v/v14
git archive 07b2d0c jaxrender | tar -x -C .v/v14
mkdir -p .v/v15
git archive 39e025f jaxrender | tar -x -C .v/v15
mkdir -p .v/v16
git archive fd3a891 jaxrender | tar -x -C .v/v16
mkdir -p .v/v19
git archive 424a5fe jaxrender | tar -x -C .v/v19
mkdir -p .v/v20
git archive c87d91d jaxrender | tar -x -C .v/v20
mkdir -p .v/v24
git archive 593a3ff jaxrender | tar -x -C .v/v24
mkdir -p .v/v25
git archive 3be237f jaxrender | tar -x -C .v/v25
for p in benchmarks/variants/*.patch; do
  name=$(basename "$p" .patch)
  mkdir -p ".v/$name"
  git archive HEAD jaxrender | tar -x -C ".v/$name"
  # A variant written against an older HEAD may no longer apply: skipped, named, not half-built.
  if ! patch -s -f --dry-run -d ".v/$name" -p1 < "$p" > /dev/null; then
    echo "skipped $name: $p does not apply to HEAD" >&2
    rm -rf ".v/$name"
    continue
  fi
  patch -s -d ".v/$name" -p1 < "$p"
done
ls .v
