#!/usr/bin/env bash
# Every benchmark in one run on the lent GPU machine, under 9 minutes, output under $OUT.
#
#   device run:  bash benchmarks/gpu_batch.sh            carry: [".whl", ".gl"]
#   a subset:    bash benchmarks/gpu_batch.sh peers scale
#   CPU smoke:   QUICK=1 OUT=/tmp/out bash benchmarks/gpu_batch.sh
#   more time for one step run alone: BUDGET_S=560 BENCH_S=550 bash benchmarks/gpu_batch.sh bench
#
# Steps (each under `timeout`, inside one overall deadline): raster (bench_raster --preset gpu),
# metrics (bench_metrics, 1080p, 60-frame batch), peers (bench_peers: jaxrenderer 0.4.0 and
# OpenGL/EGL), scale (bench_scale), bench (python -m jaxrender.bench: raster sweeps and every
# pipeline on every built-in scene at 1080p), pipelines (bench_pipelines.py, if present).
# Files in $OUT (8 at most): batch.log (everything, with step times and exit codes), env.txt,
# raster.json, peers.json, scale.json, bench.json, metrics.md, pipelines.md.
{  # the whole script is read before it runs: editing it during a run changes nothing
set -u
OUT=${OUT:?OUT must name an output folder}
mkdir -p "$OUT"
cd "$(dirname "$0")/.."
T0=$(date +%s)
DEADLINE=$((T0 + ${BUDGET_S:-535}))
LOG=$OUT/batch.log
: >"$LOG"
export PYTHONUNBUFFERED=1 MPLBACKEND=Agg

note() { echo "### $* [$(date +%T), +$(( $(date +%s) - T0 )) s]" | tee -a "$LOG"; }

# ---- carried wheels and GL loaders (device README recipes)
if ls .whl/*.whl >/dev/null 2>&1 && [ -z "${QUICK:-}" ]; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl >>"$LOG" 2>&1 || note "wheel install FAILED (peers may skip)"
fi
export PYTHONPATH=$PWD:/tmp/site${PYTHONPATH:+:$PYTHONPATH}
if ls .gl/*.deb >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && [ -z "${QUICK:-}" ]; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
  nv=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  if [ -f "$nv" ] && [ ! -f /usr/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
    export __EGL_VENDOR_LIBRARY_FILENAMES=$nv
  fi
fi
{
  date -u; uname -a; nvidia-smi 2>&1 | head -20
  python3 -c "import jax, numpy; print('jax', jax.__version__, jax.devices(), 'numpy', numpy.__version__)"
  python3 -m pip list 2>/dev/null | grep -i -E "^(jax|jaxlib|numpy|trimesh|colour|flip|xatlas|jaxrenderer|moderngl|glcontext|scikit-image) "
  ldconfig -p | grep -E "libEGL|libGL.so|libvulkan" | head
} >"$OUT/env.txt" 2>&1
cat "$OUT/env.txt" >>"$LOG"

# step NAME SECONDS CMD...: run under timeout, clipped to the overall deadline, output tee'd
step() {
  local name=$1 limit=$2 left rc t
  shift 2
  case " ${STEPS} " in *" $name "*) ;; *) return 0 ;; esac
  left=$((DEADLINE - $(date +%s)))
  [ "$limit" -gt "$left" ] && limit=$left
  if [ "$limit" -lt 15 ]; then note "$name: SKIPPED (overall deadline)"; return 0; fi
  note "$name: start (timeout ${limit} s): $*"
  t=$(date +%s)
  timeout -k 5 "$limit" "$@" 2>&1 | tee -a "$LOG" | tee "$OUT/.step" >/dev/null
  rc=${PIPESTATUS[0]}
  note "$name: exit $rc after $(( $(date +%s) - t )) s$([ "$rc" = 124 ] && echo ' (TIMED OUT)')"
  case $name in metrics|pipelines) cp "$OUT/.step" "$OUT/$name.md" ;; esac
  rm -f "$OUT/.step"
}

STEPS=${*:-raster metrics peers scale bench pipelines}
if [ -n "${QUICK:-}" ]; then  # tiny sizes: checks the plumbing on a CPU
  step raster 300 python3 benchmarks/bench_raster.py --preset cpu --repeats 2 --brute-size 64x36 --json "$OUT/raster.json"
  step metrics 300 python3 benchmarks/bench_metrics.py --width 64 --height 36 --frames 2 --repeats 2 --lib-frames 1 --only psnr ssim
  step peers 300 python3 benchmarks/bench_peers.py --tiny --repeats 2 --draws 3 --jaxrender-repeats 5 --json "$OUT/peers.json"
  step scale 400 python3 benchmarks/bench_scale.py --resolution 48x27 --frames 2 --chunk 1 --repeats 1 --raster-triangles 2000 --pipelines forward --sweep 0 --scene spheres --json "$OUT/scale.json"
  step bench 400 python3 -m jaxrender.bench --quick --sections raster pipelines --pipelines forward --json "$OUT/bench.json"
  [ -f benchmarks/bench_pipelines.py ] && step pipelines 300 python3 benchmarks/bench_pipelines.py --scenes spheres --variants forward --resolution 32x18 --repeats 1
else
  step raster "${RASTER_S:-110}" python3 benchmarks/bench_raster.py --preset gpu --repeats 100 --brute-size 1920x1080 --json "$OUT/raster.json"
  step metrics "${METRICS_S:-75}" python3 benchmarks/bench_metrics.py --width 1920 --height 1080 --frames 60 --repeats 5 --lib-frames 2
  step peers "${PEERS_S:-90}" env XLA_PYTHON_CLIENT_MEM_FRACTION=0.6 python3 benchmarks/bench_peers.py --repeats 10 --draws 50 --json "$OUT/peers.json"
  step scale "${SCALE_S:-70}" python3 benchmarks/bench_scale.py --resolution 1920x1080 --frames 16 --chunk 8 --repeats 3 --pipelines forward --sweep 8 --json "$OUT/scale.json"
  step bench "${BENCH_S:-130}" python3 -m jaxrender.bench --sections raster pipelines --resolution 1920x1080 --repeats 10 --budget $(( ${BENCH_S:-130} - 25 )) --json "$OUT/bench.json"
  [ -f benchmarks/bench_pipelines.py ] && step pipelines "${PIPELINES_S:-40}" python3 benchmarks/bench_pipelines.py --resolution 1920x1080 --repeats 10
fi
note "all done; files: $(ls "$OUT" | tr '\n' ' ')"
exit 0
}
