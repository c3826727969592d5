"""jaxrender's rasterizer beside its peers, on the same scene, resolution and device:

* jaxrenderer 0.4.0 (PyPI, ``import renderer``), depth only: its README's size (1920x1080,
  about 2.5k triangles) and 640x360 with 10k triangles (the goal: jaxrender at least 150x
  faster; benchmarks/RESULTS.md has the numbers). The goal's ratio (``speedup_vs_jaxrenderer``)
  is taken against jaxrender's ids-and-depth output (``rasterize_depth_clip``), the nearest to
  a depth render, in a frame loop of the compiled program that donates each frame's buffers
  to the next (what ``donate=`` runs); the single call's ratio (previous result kept alive,
  no donation), the same loop through the public entry point and the full VisBuffer are
  printed beside it. Its coverage (depth < 1) is
  compared with jaxrender's; it follows no exact fill rule and culls back faces, so expect
  about 99%.
* the hardware rasterizer through OpenGL/EGL (moderngl, backend "egl"): the same clip-space
  vertices drawn with a pass-through vertex shader, ``gl_PrimitiveID + 1`` written to an R32I
  target, depth test LESS on a 24-bit depth buffer, window origin set to the upper left with
  glClipControl where the driver has it (so that row 0 is the top, as in jaxrender, and the
  fill rule is applied in the same orientation). Timing: glFinish, many draws (clear + draw),
  glFinish, per-draw mean; median of repeats; also the median of single synchronised draws.
  Triangle ids are compared pixel by pixel: raw agreement; agreement with depth ties excluded
  (a differing pixel where GL's triangle has, at the pixel centre, the same window depth as
  jaxrender's within 1e-6: both answers are right); agreement with edge ties excluded as
  well (the centre within one snapping step, 1/256 px, of an edge of either triangle, where
  the two rasterizers' vertex snapping decides); and agreement on pixels away from triangle
  edges (the pixel and its 4 neighbours share one id in both images). Every difference that
  is neither tie is printed with both triangles' depths and edge distances.

The scene is the terrain of ``benchmarks/bench_raster.py`` (same mesh and camera). Every peer
is optional: a missing package or no GL prints the reason and the rest runs.

    python benchmarks/bench_peers.py --json peers.json                       # GPU
    JAX_PLATFORMS=cpu python benchmarks/bench_peers.py --tiny                # a CPU smoke run
"""

from __future__ import annotations

import argparse
import ctypes
import statistics
import sys
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

from jaxrender.bench.raster import static_args, terrain_camera, terrain_clip
from jaxrender.bench.report import dump, print_table
from jaxrender.timing import environment, time_compiled
from jaxrender.raster import rasterize_clip, rasterize_depth_clip
from jaxrender.raster.rasterize import rasterize_donating, rasterize_program
from jaxrender.raster.setup import SUBPIXEL_BITS
from jaxrender.scene.mesh import terrain_mesh

JR_CASES = [(1920, 1080, 2_500), (640, 360, 10_000)]
GL_CASES = [(1920, 1080, 2_500), (1920, 1080, 164_000), (1920, 1080, 655_000),
            (1920, 1080, 2_600_000)]
TINY_JR = [(160, 90, 500)]
TINY_GL = [(160, 90, 500), (320, 180, 10_000)]
TIE_EPS = 1e-6
EDGE_EPS = 1.0 / (1 << SUBPIXEL_BITS)  # px: one step of the snapping grid


def _cases(text):
    """'1920x1080:2500,640x360:10000' -> [(1920, 1080, 2500), (640, 360, 10000)]"""
    out = []
    for item in filter(None, text.split(",")):
        res, _, n = item.partition(":")
        w, h = res.split("x")
        out.append((int(w), int(h), int(float(n))))
    return out


# ------------------------------------------------------------------ jaxrender


def time_jaxrender(clip, faces, width, height, repeats, draws):
    """For the full VisBuffer and for ids and depth only (``rasterize_depth_clip``: the output
    jaxrenderer's depth render has), median ms of

    * ``jaxrender[_depth]_ms``: single synchronised calls of the compiled program, each
      result kept until the next call returns;
    * ``jaxrender[_depth]_loop_ms``: a frame loop of the same program, each frame donating
      the previous one's buffers (what ``donate=`` runs), as a renderer's loop would;
    * ``jaxrender[_depth]_public_loop_ms``: that loop through the public entry point, whose
      Python checks cost a frame this small about twice their own time (they also delay
      the next dispatch; benchmarks/RESULTS.md);
    * ``jaxrender[_depth]_batched_ms``: ``draws`` calls dispatched back to back with one wait
      (the throughput GL's loop measures).

    All but the last are timed interleaved, ``repeats`` calls each in 10 rounds: a frame of
    well under a millisecond is host-bound, and the host's speed drifts within a run."""
    out, steps = {}, {}
    static = static_args(faces.shape[0], width, height)
    for suffix, bary, entry in (("", True, rasterize_clip), ("_depth", False, rasterize_depth_clip)):
        t0 = time.perf_counter()
        compiled = rasterize_program.lower(clip, faces, barycentrics=bary, **static).compile()
        out[f"jaxrender{suffix}_compile_s"] = time.perf_counter() - t0
        per = []
        for _ in range(max(3, repeats // 20)):
            jax.block_until_ready(compiled(clip, faces))
            t0 = time.perf_counter()
            outs = [compiled(clip, faces) for _ in range(draws)]
            jax.block_until_ready(outs)
            per.append((time.perf_counter() - t0) / draws)
            del outs
        out[f"jaxrender{suffix}_batched_ms"] = 1e3 * statistics.median(per)
        first = compiled(clip, faces)
        steps[f"jaxrender{suffix}_ms"] = lambda _, c=compiled: c(clip, faces)
        steps[f"jaxrender{suffix}_loop_ms"] = lambda prev, b=bary, f=first: rasterize_donating(
            clip, faces, f if prev is None else prev, barycentrics=b, **static)
        steps[f"jaxrender{suffix}_public_loop_ms"] = lambda prev, e=entry: e(
            clip, faces, width, height, donate=prev)
    medians, last = _interleaved(steps, repeats)
    return out | medians, last["jaxrender_ms"]


def _interleaved(steps: dict, repeats: int, rounds: int = 10):
    """Median ms of ``state = step(state)`` per step (the state starts as None), the steps
    taking turns in ``rounds`` rounds; returns the medians and each step's last state."""
    state = dict.fromkeys(steps)
    for name, step in steps.items():
        for _ in range(3):
            state[name] = jax.block_until_ready(step(state[name]))
    samples = {name: [] for name in steps}
    for _ in range(rounds):
        for name, step in steps.items():
            for _ in range(max(1, repeats // rounds)):
                t0 = time.perf_counter()
                state[name] = jax.block_until_ready(step(state[name]))
                samples[name].append(time.perf_counter() - t0)
    return {name: 1e3 * statistics.median(v) for name, v in samples.items()}, state


# ------------------------------------------------------------------ jaxrenderer 0.4.0


def jaxrenderer_available() -> str | None:
    try:
        with warnings.catch_warnings():  # its decorators warn once per function (jaxtyping)
            warnings.simplefilter("ignore")
            import renderer  # noqa: F401
            from renderer.shaders.depth import DepthShader  # noqa: F401
    except Exception as e:  # noqa: BLE001
        return f"jaxrenderer not importable ({type(e).__name__}: {e})"
    return None


def jaxrenderer_depth(verts, faces, width, height, repeats):
    """jaxrenderer's depth-only render of the benchmark terrain through the same camera.

    jaxrenderer always culls back faces (its default primitive chooser keeps front-facing
    fragments only, front = its determinant >= 0), and the terrain's winding is the other way
    round in its convention, so it gets the faces reversed: the same surface, facing it."""
    import renderer
    from renderer.shaders.depth import DepthExtraInput, DepthShader

    cam = terrain_camera()
    rot = np.asarray(cam.rotation, np.float64)
    eye = np.asarray(cam.eye, np.float64)
    view = np.eye(4)
    view[:3, :3] = rot
    view[:3, 3] = -rot @ eye
    proj = renderer.Camera.perspective_projection_matrix(
        float(np.rad2deg(float(cam.fov_y))), width / height, float(cam.near), float(cam.far))
    viewport = renderer.Camera.viewport_matrix(jnp.zeros(2, dtype=int),
                                               jnp.array((width, height)), 1.0)
    camera = renderer.Camera.create(view=jnp.asarray(view, jnp.float32), projection=proj,
                                    viewport=viewport)

    @jax.jit
    def depth(positions, tri, camera):
        buffers = renderer.Buffers(zbuffer=jax.lax.full((width, height), 1.0), targets=())
        zbuf, _ = renderer.render(camera, DepthShader, buffers, tri,
                                  DepthExtraInput(position=positions))
        return zbuf

    tri = jnp.asarray(np.ascontiguousarray(np.asarray(faces)[:, ::-1]))
    r = time_compiled(depth, jnp.asarray(verts), tri, camera, repeats=repeats,
                      warmup=1)
    zbuf = np.asarray(r.pop("out"))  # [W, H], y up
    return {"jaxrenderer_ms": r["median_ms"], "jaxrenderer_compile_s": r["compile_s"]}, zbuf.T[::-1]


# ------------------------------------------------------------------ OpenGL through EGL

_GL_UPPER_LEFT, _GL_NEGATIVE_ONE_TO_ONE, _GL_CLIP_ORIGIN = 0x8CA2, 0x935E, 0x935C

VERTEX = """#version 330
in vec4 in_clip;
void main() { gl_Position = in_clip; }
"""
FRAGMENT = """#version 330
layout(location = 0) out int out_id;
void main() { out_id = gl_PrimitiveID + 1; }
"""


def _gl_proc(name: str, restype, *argtypes):
    egl = ctypes.CDLL("libEGL.so.1")
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    addr = egl.eglGetProcAddress(name.encode())
    return ctypes.CFUNCTYPE(restype, *argtypes)(addr) if addr else None


class GLRasterizer:
    """One EGL context; ``ids(clip, faces, w, h)`` -> int32[H, W] triangle ids (-1: empty)."""

    def __init__(self):
        import moderngl

        self.mgl = moderngl
        self.ctx = moderngl.create_context(standalone=True, backend="egl")
        self.upper_left = self._upper_left_origin()
        self.prog = self.ctx.program(vertex_shader=VERTEX, fragment_shader=FRAGMENT)
        self.info = {k: self.ctx.info.get(k) for k in ("GL_RENDERER", "GL_VERSION", "GL_VENDOR")}
        self.info["origin"] = "upper_left" if self.upper_left else "lower_left (rows flipped)"

    def _upper_left_origin(self) -> bool:
        try:
            clip_control = _gl_proc("glClipControl", None, ctypes.c_uint, ctypes.c_uint)
            get_int = _gl_proc("glGetIntegerv", None, ctypes.c_uint, ctypes.POINTER(ctypes.c_int))
            if clip_control is None or get_int is None:
                return False
            clip_control(_GL_UPPER_LEFT, _GL_NEGATIVE_ONE_TO_ONE)
            v = ctypes.c_int(0)
            get_int(_GL_CLIP_ORIGIN, ctypes.byref(v))
            return v.value == _GL_UPPER_LEFT
        except Exception:  # noqa: BLE001
            return False

    def setup(self, clip, faces, width, height):
        ctx, mgl = self.ctx, self.mgl
        self.release()
        self.vbo = ctx.buffer(np.ascontiguousarray(clip, np.float32).tobytes())
        self.ibo = ctx.buffer(np.ascontiguousarray(faces, np.int32).tobytes())
        self.vao = ctx.vertex_array(self.prog, [(self.vbo, "4f", "in_clip")],
                                    index_buffer=self.ibo, index_element_size=4)
        self.color = ctx.renderbuffer((width, height), components=1, dtype="i4")
        self.depth = ctx.depth_renderbuffer((width, height))
        self.fbo = ctx.framebuffer([self.color], self.depth)
        self.fbo.use()
        ctx.viewport = (0, 0, width, height)
        ctx.disable(mgl.CULL_FACE | mgl.BLEND)
        ctx.enable(mgl.DEPTH_TEST)
        ctx.depth_func = "<"
        self.size = (width, height)

    def draw(self):
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        self.vao.render(self.mgl.TRIANGLES)

    def read_ids(self):
        w, h = self.size
        raw = np.frombuffer(self.fbo.read(components=1, dtype="i4", attachment=0), np.int32)
        ids = raw.reshape(h, w) - 1
        return ids if self.upper_left else ids[::-1].copy()

    def time(self, draws, repeats):
        self.draw()
        self.ctx.finish()
        per, sync = [], []
        for _ in range(repeats):
            self.ctx.finish()
            t0 = time.perf_counter()
            for _ in range(draws):
                self.draw()
            self.ctx.finish()
            per.append((time.perf_counter() - t0) / draws)
        for _ in range(max(repeats, 5)):
            self.ctx.finish()
            t0 = time.perf_counter()
            self.draw()
            self.ctx.finish()
            sync.append(time.perf_counter() - t0)
        return {"gl_ms": 1e3 * statistics.median(per), "gl_sync_ms": 1e3 * statistics.median(sync)}

    def release(self):
        for k in ("fbo", "color", "depth", "vao", "ibo", "vbo"):
            obj = getattr(self, k, None)
            if obj is not None:
                obj.release()
                setattr(self, k, None)


def gl_available():
    try:
        return GLRasterizer(), None
    except Exception as e:  # noqa: BLE001
        return None, f"OpenGL/EGL unavailable ({type(e).__name__}: {e})"


# ------------------------------------------------------------------ agreement


def _window(clip, width, height):
    c = np.asarray(clip, np.float64)
    w = c[:, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (c[:, 0] / w + 1.0) * 0.5 * width
        y = (1.0 - c[:, 1] / w) * 0.5 * height  # image rows, 0 at the top
        z = (c[:, 2] / w + 1.0) * 0.5
    return x, y, z, w


def depth_at(clip, faces, tri, px, py, width, height, with_inside=False):
    """Window depth of triangle ``tri`` at pixel centres (px + .5, py + .5), float64; NaN for a
    triangle with a vertex behind the eye (clipped: its plane is not the drawn one). With
    ``with_inside`` also whether the centre lies in the triangle (unsnapped vertices, edges
    included) and its distance in pixels to the triangle's nearest edge."""
    x, y, z, w = _window(clip, width, height)
    f = np.asarray(faces)[tri]
    X, Y, Z, Wv = x[f], y[f], z[f], w[f]
    sx, sy = px + 0.5, py + 0.5

    def edge(i, j):
        return (X[:, j] - X[:, i]) * (sy - Y[:, i]) - (Y[:, j] - Y[:, i]) * (sx - X[:, i])

    edges = np.stack([edge(1, 2), edge(2, 0), edge(0, 1)], -1)
    area = np.sum(edges, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = edges / area[:, None]
        d = np.sum(lam * Z, -1)
    d = np.where(np.all(Wv > 0, -1), d, np.nan)
    if not with_inside:
        return d
    lengths = np.stack([np.hypot(X[:, j] - X[:, i], Y[:, j] - Y[:, i])
                        for i, j in ((1, 2), (2, 0), (0, 1))], -1)
    return d, np.all(lam >= 0, -1), np.min(np.abs(edges) / lengths, -1)


def _interior(ids):
    """Pixels whose 4 neighbours hold the same id (image border pixels count as edges)."""
    m = np.zeros(ids.shape, bool)
    c = ids[1:-1, 1:-1]
    m[1:-1, 1:-1] = ((c == ids[:-2, 1:-1]) & (c == ids[2:, 1:-1])
                     & (c == ids[1:-1, :-2]) & (c == ids[1:-1, 2:]))
    return m


def compare_ids(ours, theirs, our_depth, clip, faces, width, height) -> dict:
    """Pixel-by-pixel agreement of triangle ids. Two kinds of difference are ties, where both
    answers are right: a depth tie (GL's triangle has, at the pixel centre, the same window
    depth as ours within TIE_EPS) and an edge tie (the centre lies within one snapping step,
    EDGE_EPS px, of an edge of either triangle: the fill decision then rests on how each
    rasterizer snaps the vertices, and GL's hardware does that its own way). Differences that
    are neither are printed (up to 20), and the first three edge ties."""
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    same = ours == theirs
    diff_y, diff_x = np.nonzero(~same)
    both = (ours[diff_y, diff_x] >= 0) & (theirs[diff_y, diff_x] >= 0)
    ties = edge_ties = 0
    if both.any():
        py, px = diff_y[both], diff_x[both]
        d_theirs = depth_at(clip, faces, theirs[py, px], px, py, width, height)
        d_ours = np.asarray(our_depth, np.float64)[py, px]
        tie = np.abs(d_theirs - d_ours) <= TIE_EPS
        ties = int(np.sum(tie))
        py, px, d_ours, d_theirs = py[~tie], px[~tie], d_ours[~tie], d_theirs[~tie]
        t_ours, t_gl = ours[py, px], theirs[py, px]
        _, in_o, e_o = depth_at(clip, faces, t_ours, px, py, width, height, True)
        _, in_g, e_g = depth_at(clip, faces, t_gl, px, py, width, height, True)
        # A triangle with a vertex behind the eye has no drawn plane here (NaN depth): never
        # a tie.
        edge = (np.minimum(e_o, e_g) <= EDGE_EPS) & np.isfinite(d_theirs)
        edge_ties = int(np.sum(edge))
        shown = np.concatenate([np.nonzero(~edge)[0][:20], np.nonzero(edge)[0][:3]])
        for i in shown:  # every real difference (up to 20), and a few edge ties as evidence
            print(f"  pixel ({px[i]}, {py[i]}){' (edge tie)' if edge[i] else ''}: ours {t_ours[i]}"
                  f" at depth {d_ours[i]:.9f} (centre inside: {bool(in_o[i])}, {e_o[i]:.2e} px "
                  f"from an edge), GL {t_gl[i]} at {d_theirs[i]:.9f} (inside: {bool(in_g[i])}, "
                  f"{e_g[i]:.2e} px from an edge)", flush=True)
    interior = _interior(ours) & _interior(theirs)
    n = ours.size
    return {
        "ids_agree": float(np.mean(same)),
        "ids_agree_excl_ties": float(np.sum(same) / max(n - ties, 1)),
        "ids_agree_excl_all_ties": float(np.sum(same) / max(n - ties - edge_ties, 1)),
        "ids_agree_interior": float(np.mean(same[interior])) if interior.any() else float("nan"),
        "interior_fraction": float(np.mean(interior)),
        "differing_pixels": int(n - np.sum(same)),
        "depth_ties": ties,
        "edge_ties": edge_ties,
        "coverage_only_diffs": int(np.sum(~both)),
    }


# ------------------------------------------------------------------ main


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jaxrenderer-cases", type=_cases, help="WxH:triangles,... (default: "
                    "1920x1080:2500,640x360:10000)")
    ap.add_argument("--gl-cases", type=_cases, help="WxH:triangles,... (default: 1920x1080 at "
                    "2500, 164000, 655000, 2600000)")
    ap.add_argument("--tiny", action="store_true", help="CPU smoke sizes")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--draws", type=int, default=50, help="draws per timed GL/jaxrender batch")
    ap.add_argument("--jaxrender-repeats", type=int, default=300,
                    help="single synchronised jaxrender calls timed per case")
    ap.add_argument("--no-jaxrenderer", action="store_true")
    ap.add_argument("--no-gl", action="store_true")
    ap.add_argument("--json")
    a = ap.parse_args(argv)
    jr_cases = a.jaxrenderer_cases or (TINY_JR if a.tiny else JR_CASES)
    gl_cases = a.gl_cases or (TINY_GL if a.tiny else GL_CASES)
    env = environment()
    print(env, flush=True)
    skipped = {}
    rows = []
    payload = {"environment": env, "skipped": skipped, "rows": rows}

    jr_reason = "--no-jaxrenderer" if a.no_jaxrenderer else jaxrenderer_available()
    if jr_reason:
        skipped["jaxrenderer"] = jr_reason
        print(f"skip jaxrenderer: {jr_reason}", flush=True)
    gl, gl_reason = (None, "--no-gl") if a.no_gl else gl_available()
    if gl_reason:
        skipped["gl"] = gl_reason
        print(f"skip OpenGL: {gl_reason}", flush=True)
    else:
        payload["gl"] = gl.info
        print(f"OpenGL: {gl.info}", flush=True)

    cases = sorted(set(([] if jr_reason else jr_cases) + ([] if gl_reason else gl_cases)),
                   key=lambda c: (c[2], c[0]))
    if not cases:  # still time jaxrender alone, so the script says something useful
        cases = sorted(set(jr_cases + gl_cases), key=lambda c: (c[2], c[0]))
    for width, height, n in cases:
        clip, faces = terrain_clip(n, width, height)
        row = dict(resolution=f"{width}x{height}", triangles=int(faces.shape[0]))
        try:
            t, vis = time_jaxrender(clip, faces, width, height, a.jaxrender_repeats, a.draws)
            row.update(t)
        except Exception as e:  # noqa: BLE001
            row["jaxrender_error"] = f"{type(e).__name__}: {e}"[:200]
            vis = None
        ours = None if vis is None else np.asarray(vis.tri_id)
        if not jr_reason and (width, height, n) in jr_cases:
            try:
                v, f = terrain_mesh(n)
                with warnings.catch_warnings():  # jaxtyping warns at every trace
                    warnings.simplefilter("ignore")
                    t, z = jaxrenderer_depth(v, f, width, height, max(2, a.repeats // 2))
                row.update(t)
                if ours is not None:
                    row["jaxrenderer_coverage_agree"] = float(np.mean((z < 1.0) == (ours >= 0)))
                    # The goal compares like with like: depth (and ids) against depth, frame
                    # after frame; the single call and the full VisBuffer are shown beside it.
                    jr = row["jaxrenderer_ms"]
                    row["speedup_vs_jaxrenderer"] = jr / row["jaxrender_depth_loop_ms"]
                    row["speedup_single_call"] = jr / row["jaxrender_depth_ms"]
                    row["speedup_full_visbuffer"] = jr / row["jaxrender_loop_ms"]
            except Exception as e:  # noqa: BLE001
                row["jaxrenderer_error"] = f"{type(e).__name__}: {e}"[:200]
        if gl is not None and (width, height, n) in gl_cases:
            try:
                clip_np, faces_np = np.asarray(clip), np.asarray(faces)
                gl.setup(clip_np, faces_np, width, height)
                row.update(gl.time(a.draws, a.repeats))
                theirs = gl.read_ids()
                if ours is not None:
                    row.update(compare_ids(ours, theirs, vis.depth, clip_np, faces_np, width, height))
                    row["gl_ms_over_jaxrender_ms"] = row["gl_ms"] / row["jaxrender_ms"]
                gl.release()
            except Exception as e:  # noqa: BLE001
                row["gl_error"] = f"{type(e).__name__}: {e}"[:200]
        rows.append(row)
        print(row, flush=True)
        dump(a.json, payload)

    print("\n## jaxrender vs jaxrenderer 0.4.0 (depth only) and OpenGL (ids), median ms\n")
    print_table(rows, ["resolution", "triangles", "jaxrender_ms", "jaxrender_loop_ms",
                       "jaxrender_depth_ms", "jaxrender_depth_loop_ms",
                       "jaxrender_depth_public_loop_ms", "jaxrender_batched_ms",
                       "jaxrender_depth_batched_ms", "jaxrender_compile_s", "jaxrenderer_ms",
                       "speedup_vs_jaxrenderer", "speedup_single_call", "speedup_full_visbuffer",
                       "gl_ms", "gl_sync_ms", "gl_ms_over_jaxrender_ms"])
    print("\n## triangle-id agreement with OpenGL\n")
    print_table([r for r in rows if "ids_agree" in r],
                ["resolution", "triangles", "ids_agree", "ids_agree_excl_ties",
                 "ids_agree_excl_all_ties", "ids_agree_interior", "interior_fraction",
                 "differing_pixels", "depth_ties", "edge_ties", "coverage_only_diffs"])
    if skipped:
        print(f"\nskipped: {skipped}")
    dump(a.json, payload)
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
