#!/usr/bin/env bash
# Issue 23 before/after in one device call: per-frame time inside a 16-frame sequence at
# 1920x1080 for the pipelines over their targets, the old code (a tree of the commit named by
# BEFORE, unpacked in .before/) and this checkout side by side, plus dispatch chunk variants.
#   prepare: mkdir .before && git archive $BEFORE jaxrender benchmarks | tar -x -C .before
#   device run (carry .whl, .before): bash benchmarks/gpu_issue23.sh
set -u
OUT=${OUT:?OUT must name an output folder}
cd "$(dirname "$0")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
SCENES=${SCENES:-stripes thin room}
ARGS="--frames 16 --rounds 5 --no-single --scenes $SCENES"
LOG=$OUT/issue23.md
if [ -d .before ]; then
  echo "## before" | tee -a "$LOG"
  PYTHONPATH=$PWD/.before:/tmp/site timeout 200 python3 .before/benchmarks/bench_sequence.py \
    $ARGS --pipelines ${BEFORE_PIPES:-forward visbuffer dacs deferred} 2>&1 | quiet \
    | tail -${BEFORE_ROWS:-16} | tee -a "$LOG"
fi
echo "## after" | tee -a "$LOG"
PYTHONPATH=$PWD:/tmp/site timeout 260 python3 benchmarks/bench_sequence.py $ARGS \
  --pipelines ${AFTER_PIPES:-forward visbuffer dacs deferred} 2>&1 | quiet | tee -a "$LOG"
