"""The hardware rasterizer through OpenGL/EGL (moderngl, backend "egl"), for bench_peers.py.

The same clip-space vertices are drawn with a pass-through vertex shader, ``gl_PrimitiveID + 1``
written to an R32I target, depth test LESS on a 24-bit depth buffer, the window origin set to
the upper left with glClipControl where the driver has it (so that row 0 is the top, as in
jaxrender, and the fill rule is applied in the same orientation).
"""

from __future__ import annotations

import ctypes
import statistics
import time

import numpy as np

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
