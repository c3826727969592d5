"""Frame time of the forward, deferred and visibility-buffer pipelines per scene (honest timing:
AOT compile timed apart, warm-up, block_until_ready, median of repeats). Prints a markdown table
with the device and JAX version, and the shading counts beside the times.

    python benchmarks/bench_pipelines.py --scenes foliage room many_small --resolution 320x180 \
        --repeats 10
    python benchmarks/bench_pipelines.py --variants forward forward:z_prepass=true \
        visbuffer:vrs=fixed
"""

from __future__ import annotations

import argparse

from jaxrender.bench.pipelines import time_pipelines
from jaxrender.bench.report import print_table
from jaxrender.parsing import help_summary, resolution_arg
from jaxrender.timing import environment

DEFAULT_VARIANTS = ("forward", "forward:z_prepass=true", "deferred", "visbuffer",
                    "visbuffer:vrs=fixed")
COLUMNS = ["scene", "pipeline", "median_ms", "compile_s", "shade_invocations", "helper_lanes",
           "overshading", "waves", "lane_utilization", "bytes_intermediate", "skipped"]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=help_summary(__doc__))
    ap.add_argument("--scenes", nargs="+", default=["foliage", "room", "spheres"],
                    help="names or name:key=value,...")
    ap.add_argument("--variants", nargs="+", default=list(DEFAULT_VARIANTS),
                    help="pipelines as names or name:key=value,...")
    ap.add_argument("--resolution", type=resolution_arg, default="160x90")
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args(argv)
    w, h = a.resolution
    info = environment()
    print(f"device: {info['device']}, jax {info['jax_version']}, {w}x{h}, "
          f"median of {a.repeats} after 1 warm-up\n")
    print_table(time_pipelines(a.scenes, a.variants, w, h, repeats=a.repeats), COLUMNS)


if __name__ == "__main__":
    main()
