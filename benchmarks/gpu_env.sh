# Sourced by the device-call scripts: the checkout's root as the working folder, the carried
# wheels (.whl/: trimesh, colour-science, xatlas) installed into /tmp/site, unbuffered output,
# no GPU preallocation, quiet() to drop XLA's log lines, trees() and side_by_side() to run the
# sequence bench in several trees side by side (each run's whole output kept in a log), a tree
# not carried refused by tree_root(), prof() for a program's kernels by scope,
# layer_bench() for the shader-cost layers bench, time_work() for the time-work fits,
# cached_compiles() and S8 for the side-by-side sequence parts, bundle_out() to pack $OUT into
# one file, and targets_first() to run issue 23's rows first on
# an H200.
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "${BASH_SOURCE[0]}")/.."
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
  --target /tmp/site .whl/*.whl || exit 1
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
quiet() { grep -v "^WARNING\|^I0000\|^E0000\|^W0000"; }
# --outputs all: the older trees know no other, and a comparison times like with like.
B="python3 benchmarks/bench_sequence.py --no-single --checksum --resolution 1920x1080 --outputs all"
# tree_root TREE: the folder whose jaxrender a tree's run imports (after: this checkout, else
# .v/TREE); a tree not carried fails loudly: the bench scripts put this checkout on the path
# when PYTHONPATH names no jaxrender, so it would run this checkout under the tree's name.
tree_root() {
  if [ "$1" = after ]; then echo "$PWD"; return; fi
  [ -d "$PWD/.v/$1/jaxrender" ] || { echo "tree $1: no .v/$1/jaxrender (carry it)" >&2; return 1; }
  echo "$PWD/.v/$1"
}
# trees FILE SECONDS "TREE ..." BENCH-ARGS...: the bench in each tree (after: this checkout,
# else .v/TREE), its rows tagged with the tree and appended to $OUT/FILE.
trees() {
  local file=$1 limit=$2 names=$3 t R
  shift 3
  for t in $names; do
    R=$(tree_root "$t") || { echo "{\"tree\": \"$t\", \"error\": \"not carried\"}" \
      | tee -a "$OUT/$file"; continue; }
    PYTHONPATH=$R:/tmp/site timeout -k 5 "$limit" $B "$@" 2>&1 | quiet | grep '^{' \
      | sed "s/^{/{\"tree\": \"$t\", /" | tee -a "$OUT/$file"
  done
}
# side_by_side NAME SECONDS "TREE ..." ARGS...: the caller's $S in each tree (after: this
# checkout, else .v/TREE), then again in the reverse order (A B B A; ORDERS=1: once), its
# tables tagged with the tree and the pass, in $OUT/NAME.md. The tree that ran second was
# 0.05-0.21 ms a frame faster in both of two calls (RESULTS.md, thirtieth session), so one
# order alone cannot tell a change from its place in the call.
side_by_side() {
  local name=$1 limit=$2 names=$3 t R pass order
  shift 3
  order=$names
  for pass in $(seq 1 "${ORDERS:-2}"); do
    for t in $order; do
      R=$(tree_root "$t") || { echo "$t ($pass): skipped" | tee -a "$OUT/$name.md"; continue; }
      # The whole output in a log beside the table: a run that prints no row says why there.
      PYTHONPATH=$R:/tmp/site timeout -k 5 "$limit" $S "$@" \
        --json "$OUT/${name}_${t}_$pass.json" 2>&1 | quiet | tee "$OUT/${name}_${t}_$pass.log" \
        | grep '^|' | sed "s/^/$t ($pass): /" | tee -a "$OUT/$name.md"
    done
    order=$(printf '%s\n' $order | tac | tr '\n' ' ')
  done
}
prof() {  # prof PIPELINE SCENE SECONDS SCOPE...: the pipeline's kernels on SCENE by named scope
  local pipe=$1 scene=$2 limit=$3
  shift 3
  PYTHONPATH=$PWD:/tmp/site timeout -k 5 "$limit" python3 benchmarks/profile_kernels.py "$pipe" \
    --scene "$scene" --top 25 --calls 3 $(printf -- '--scope %s ' "$@") 2>&1 | quiet \
    | tee -a "$OUT/profile.md"
}
# time_work NAME SECONDS ARGS...: bench_time_work.py with ARGS, its rows in $OUT/NAME.jsonl and
# its fits in $OUT/NAME.md.
time_work() {
  local name=$1 limit=$2
  shift 2
  PYTHONPATH=$PWD:/tmp/site timeout -k 5 "$limit" python3 benchmarks/bench_time_work.py "$@" \
    --out "$OUT/$name.jsonl" 2>&1 | quiet | grep -v '^{' | tee -a "$OUT/$name.md"
}
# layer_bench FILE LABEL [FLAG]: the layers bench (bench_cost_layers.py) in $TREE (default this
# checkout), its rows in $OUT/FILE.jsonl and its table in $OUT/FILE.md.
layer_bench() {
  local file=$1 label=$2
  shift 2
  PYTHONPATH=${TREE:-$PWD}:/tmp/site timeout -k 5 150 python3 benchmarks/bench_cost_layers.py \
    --scenes foliage room --sizes 4096 16384 65536 0 --repeats 10 --label "$label" "$@" \
    --out "$OUT/$file.jsonl" 2>&1 | quiet | tee -a "$OUT/$file.md"
}
# cached_compiles: JAX's persistent cache for the side-by-side parts (a tree's second pass
# loads its programs), and S8, the 8-frame images-only sequence bench they time.
cached_compiles() {
  export JAX_COMPILATION_CACHE_DIR=/tmp/jcc JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0 \
    JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES=0
}
S8="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
# bundle_out: every file in $OUT but the bundle appended to $OUT/bundle.tar and removed. A call
# brings back at most 8 files from $OUT (device README); a script that calls this after each
# part leaves the bundle and the running part's files, so a call cut at its limit still
# returns every finished part.
bundle_out() {
  local f files=()
  for f in "$OUT"/*; do
    [ -f "$f" ] && [ "$(basename "$f")" != bundle.tar ] && files+=("$(basename "$f")")
  done
  [ ${#files[@]} -eq 0 ] || tar -rf "$OUT/bundle.tar" -C "$OUT" --remove-files "${files[@]}"
}
# targets_first "PARTS": the parts, with `targets` (issue 23's real-time rows, whose targets are
# an H200's) moved first when the card is an H200, unless NO_AUTO_TARGETS is set (a script
# handing one part to another).
targets_first() {
  local parts=$1
  if [ -z "${NO_AUTO_TARGETS:-}" ] && nvidia-smi --query-gpu=name --format=csv,noheader \
    | grep -q H200; then
    parts="targets ${parts/targets/}"
  fi
  echo "$parts"
}
