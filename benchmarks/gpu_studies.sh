#!/usr/bin/env bash
# Run the bundled studies on a GPU machine and pack their results and figures into $OUT.
# Studies run side by side (compiles are CPU-bound; the GPU is shared, each process takes a
# fraction of its memory). Each study is resumable, so a run cut by its timeout keeps its rows.
#   bash benchmarks/gpu_studies.sh [STUDY ...]      (default: the four figure studies)
set -u
cd "$(dirname "$0")/.."
OUT="${OUT:-/tmp/out}"; mkdir -p "$OUT"
if ls .whl/*.whl >/dev/null 2>&1; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl && export PYTHONPATH="$PWD:/tmp/site"
else
  export PYTHONPATH="$PWD"
fi
export JAXRENDER_CACHE=/tmp/jaxrender-cache XLA_PYTHON_CLIENT_MEM_FRACTION=0.2 PYTHONUNBUFFERED=1
studies=("$@"); [ ${#studies[@]} -gt 0 ] || studies=(pipelines_overview dacs_vs_checkerboard temporal_stability hard_cases)
limit="${STUDY_S:-480}"
for s in "${studies[@]}"; do
  ( timeout "$limit" python3 -m jaxrender study "studies/$s.toml" --out "runs/$s" --no-progress \
      > "runs_$s.log" 2>&1; echo "exit $?" >> "runs_$s.log" ) &
done
wait
for s in "${studies[@]}"; do
  python3 -m jaxrender figures "runs/$s" >> "runs_$s.log" 2>&1
  tail -25 "runs_$s.log"
done
# One archive per study (figures, tables, resolved study, environment, log): each stays under
# the device tool's 16 MiB per file; the stores and image npz files stay on the machine.
for s in "${studies[@]}"; do
  tar czf "$OUT/$s.tgz" --exclude='*.npz' --exclude='results.jsonl' "runs/$s" "runs_$s.log"
done
ls -la "$OUT"
