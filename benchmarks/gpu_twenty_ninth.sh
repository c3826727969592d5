#!/usr/bin/env bash
# Written in the twenty-ninth session (carry [".whl", ".v"]; .v/base and .v/ckmat as
# gpu_twenty_eighth.sh's header builds them). Calls as they ran, one H100 each:
#   1. bash benchmarks/gpu_twenty_ninth.sh dacsprof grouped ckmat
#   2. bash benchmarks/gpu_twenty_ninth.sh fused   (this tree then had fusion.sum_together;
#      it is now reverted, so a rerun takes it from .v/fused, built as .v/ckmat is, with
#      benchmarks/variants/layers_one_reduce.patch)
# Prepared for the next session, one call (.v/base needed):
#   bash benchmarks/gpu_twenty_ninth.sh dacsprof2 ckmat2 ckfits
# dacsprof: DACS and deferred on foliage at shader costs 0 and 256, kernels by scope
#   (profile_kernels.py --shader-cost), and DACS's optimized programs at cost 256. DACS's
#   slope was 1.6-2.0x deferred's (twenty-eighth session) with about the same lanes launched
#   per point shaded; per lane and layer 11.6 ps against 6.1. Which kernels grow with the cost
#   in each, and by how much per lane launched? Prediction: DACS's shade scope grows by about
#   0.34 ms (cost 0 -> 256) and deferred's lighting by about 1.6; the DACS kernels that grow
#   are its shade reductions, each launch 4,096-65,536 lanes.
# grouped, ckmat: as in gpu_twenty_eighth.sh (prepared there, not run).
# ckmat2: checkerboard with its mask stored (this tree, since a787d68) against
#   .v/base, in the reverse order of ckmat's call (this tree first).
# dacsprof2: as dacsprof at cost 256 alone, with each scope's longest kernels listed
#   (profile_kernels.py --scope-top): which of DACS's shade kernels take its 0.34 ms.
# ckfits: checkerboard's and deferred's fits on foliage in this tree (after ckmat).
# fused: the layers' three colour sums in one variadic reduce (fusion.sum_together), against
#   .v/base (81cc791's jaxrender: three reduces). dacsdump showed each layer's shared term
#   stored as f32[257, lanes] and read back by two reductions (R fused into the image's
#   scatter, G and B together); on the CPU the one reduce stores no per-layer array (room's
#   4,096-lane launch at cost 256: 102 MB of temporaries -> 2 MB). The layers bench and
#   foliage's fits in both trees. Prediction: foliage's full-screen layer evaluation 11.8 ->
#   5-8 ps, room's 105 -> 50-80; deferred's slope 20-50% lower; DACS's slope within 1.4x of
#   deferred's.
. "$(dirname "$0")/gpu_env.sh"
for part in "$@"; do
  if [ "$part" = dacsprof ]; then
    for cost in 0 256; do
      prof_args="--scene foliage --shader-cost $cost --top 14 --calls 3"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py dacs \
        $prof_args --scope visibility --scope decide --scope interpolate --scope shade \
        --scope dacs 2>&1 | quiet | tee -a "$OUT/dacsprof.md"
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py deferred \
        $prof_args --scope visibility --scope gbuffer --scope plan --scope lighting \
        2>&1 | quiet | tee -a "$OUT/dacsprof.md"
    done
    XLA_FLAGS="--xla_dump_to=/tmp/dacsdump --xla_dump_hlo_as_text" PYTHONPATH=$PWD:/tmp/site \
      timeout -k 5 90 python3 benchmarks/profile_kernels.py dacs --scene foliage \
      --shader-cost 256 --top 4 --calls 1 2>&1 | quiet > /dev/null
    (cd /tmp/dacsdump && tar -czf "$OUT/dacsdump.tar.gz" $(ls | grep after_optimizations.txt))
  elif [ "$part" = dacsprof2 ]; then
    for p in "dacs --scope shade --scope decide" "deferred --scope lighting --scope gbuffer"; do
      PYTHONPATH=$PWD:/tmp/site timeout -k 5 90 python3 benchmarks/profile_kernels.py $p \
        --scene foliage --shader-cost 256 --top 6 --calls 3 --scope-top 14 2>&1 | quiet \
        | tee -a "$OUT/dacsprof2.md"
    done
  elif [ "$part" = ckmat2 ]; then
    S="python3 benchmarks/bench_sequence.py --frames 8 --rounds 3 --no-single --outputs images"
    side_by_side ckmat2 120 "after base" --scenes foliage room glass --pipelines checkerboard
  elif [ "$part" = ckfits ]; then
    PYTHONPATH=$PWD:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
      --scenes foliage --pipelines deferred checkerboard --costs 0 256 --frames 8 --repeats 5 \
      --budget 140 --out "$OUT/ckmat2_fits.jsonl" 2>&1 | quiet | grep -v '^{' \
      | tee -a "$OUT/ckmat2_fits.md"
  elif [ "$part" = fused ]; then
    grep -q sum_together .v/fused/jaxrender/fusion.py || exit 1
    for t in base fused; do  # each tree's shader at cost 256: temporaries, reduce kernels
      R=$PWD/.v/$t
      PYTHONPATH=$R:/tmp/site timeout -k 5 60 python3 -P - <<'PY' 2>&1 | quiet | sed "s/^/$t: /" \
        | tee -a "$OUT/fused_hlo.md"
import re
import jax, jax.numpy as jnp, numpy as np
from jaxrender.shading import load_lit_scene, shade
from jaxrender.shading.surface import surface_points
from jaxrender.study.backend import with_shader_cost
for name in ("foliage", "room"):
    scene = with_shader_cost(load_lit_scene(name), 256)
    rng = np.random.default_rng(0)
    for n in (4096, 65536):
        tri = rng.integers(0, scene.faces.shape[0], n).astype(np.int32)
        bary = rng.dirichlet(np.ones(3), n).astype(np.float32)
        z = np.zeros((n, 3), np.float32)
        pts = tuple(map(jnp.asarray, (tri, bary, z, z)))
        c = jax.jit(lambda s, p: shade(surface_points(s, s.camera, *p), s)).lower(
            scene, pts).compile()
        txt = c.as_text()
        print(name, n, "temp bytes", c.memory_analysis().temp_size_in_bytes, "reduce fusions",
              len(re.findall(r"= \S+ fusion\(.*kind=kInput, calls=%fused_reduce", txt)),
              "reduces", len(re.findall(r" reduce\(", txt)))
PY
    done
    TREE=$PWD/.v/base layer_bench fused base --sizes 4096 65536 0
    TREE=$PWD/.v/fused layer_bench fused fused --sizes 4096 65536 0
    for t in base fused; do
      R=$PWD/.v/$t
      P="deferred dacs"
      PYTHONPATH=$R:/tmp/site timeout -k 5 150 python3 benchmarks/bench_time_work.py \
        --scenes foliage --pipelines $P --costs 0 256 --frames 8 --repeats 5 \
        --budget 140 --out "$OUT/fused_fits.jsonl" --label $t 2>&1 | quiet | grep -v '^{' \
        | sed "s/^/$t: /" | tee -a "$OUT/fused_fits.md"
    done
  else
    OUT=$OUT bash benchmarks/gpu_twenty_eighth.sh "$part"
  fi
done
exit 0
