#!/usr/bin/env bash
# The end of a session's device time, one call: the sources' report (its studies run at their
# bundled sizes, resumable), then the temporal_stability and tads_comparison studies; each step
# under its own limit, everything tarred under $OUT whatever finished.
#   device run (carry .whl): bash benchmarks/gpu_session_end.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
mkdir -p "$OUT/runs"
timeout ${REPORT_S:-240} python3 -m jaxrender report --runs "$OUT/runs/seeds" \
  --out "$OUT/runs/seeds_report" --no-progress 2>&1 | quiet | tail -${TAIL:-25}
for s in ${STUDIES:-temporal_stability tads_comparison}; do
  timeout ${STUDY_S:-100} python3 -m jaxrender study $s --out "$OUT/runs/$s" --no-progress \
    2>&1 | quiet | tail -14
done
# The tables first, flat (they come back even if the call's limit stops the tarball below).
mkdir -p "$OUT/tables"
for f in "$OUT"/runs/*/results.csv "$OUT"/runs/*/summary.csv "$OUT"/runs/seeds/*/*.csv; do
  [ -f "$f" ] && cp "$f" "$OUT/tables/$(basename "$(dirname "$f")")_$(basename "$f")"
done
# A file over 16 MiB does not come back from the device: keep the tables and PNG figures.
find "$OUT/runs" \( -name "*.pdf" -o -name "*.npz" \) -delete
tar -czf "$OUT/runs.tgz" -C "$OUT" runs && rm -rf "$OUT/runs"
