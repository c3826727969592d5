"""The one place a pipeline is compiled and run: ``render`` (one step from ``init``) and
``render_sequence`` (a ``lax.scan`` of ``step`` over a camera path), for every registered
pipeline alike.

Both go through one jitted function, ``_program``, whose static arguments are the Pipeline,
the config (its TRACED_FIELDS replaced by their defaults), the mode (one frame, or a
sequence with a number of warm-up frames to drop) and the outputs (``"all"``: images, counts
and views; ``"images"``: the images and the overflow count alone, so that XLA drops every
computation only the counts and views read, which is what a timed frame should cost); the
scene, the pipeline's prepared static data, the cameras and the traced config fields are its
arguments. So moving the camera or sweeping a traced field never recompiles, and a sequence
compiles once per (scene shape, path length, config).

``lower`` and ``bind`` split the ahead-of-time path in two picklable halves (the study compiles
in worker processes); ``compile`` joins them. Every result passes ``check_overflow``: a frame
whose ``overflow`` count is non-zero raises PipelineOverflow, naming the pipeline, the frames
and what to raise: static shapes mean capacities, and an image with pixels dropped for want of
one must never pass for a result. Under an outer trace the count stays in the Frame and the
image is NaN.
"""

from __future__ import annotations

import copy
import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

import jaxrender.pipelines.taa as taa
from jaxrender import memory_maps
from jaxrender.scene.animation import pose
from jaxrender.scene.camera import Camera
from jaxrender.shading.shadow import with_shadow_map
from jaxrender.types import Frame


class PipelineOverflow(OverflowError):
    """A frame exceeded a capacity of its pipeline; its work would have been dropped."""


# ---------------------------------------------------------------- traced config fields


def split_config(cfg) -> tuple[Any, dict]:
    """(cfg with its TRACED_FIELDS at their defaults, {field: value as an array})."""
    names = type(cfg).TRACED_FIELDS
    if not names:
        return cfg, {}
    defaults = {f.name: f.default for f in dataclasses.fields(cfg) if f.name in names}
    # The dtype follows the field's default, so a threshold given as 0 or 0.0 is one program.
    dtype = lambda d: jnp.float32 if isinstance(d, float) else jnp.int32  # noqa: E731
    traced = {n: jnp.asarray(getattr(cfg, n), dtype(defaults[n])) for n in names}
    return dataclasses.replace(cfg, **defaults), traced


def join_config(static_cfg, traced: dict):
    """The config a step sees inside the program: the static one with the traced values set.
    Set without __init__, whose checks need concrete values; the values were checked when the
    user's config was built."""
    if not traced:
        return static_cfg
    cfg = copy.copy(static_cfg)
    for name, value in traced.items():
        object.__setattr__(cfg, name, value)
    return cfg


# ---------------------------------------------------------------- the program


def _first(cameras: Camera) -> Camera:
    return jax.tree_util.tree_map(lambda a: a[0], cameras)


def _posed(scene, t):
    """The scene at frame ``t``; a moving scene's shadow map follows its objects."""
    if getattr(scene, "animation", None) is None:  # a scene of another kind (a test double)
        return scene
    with jax.named_scope("animation"):
        posed = pose(scene, t)
        return with_shadow_map(posed) if posed.shadow is not None else posed


def _init(pipe, scene, static, camera, cfg):
    if not cfg.taa:
        return pipe.init(scene, static, camera, cfg)
    return (pipe.init(scene, static, taa.jittered(camera, jnp.int32(0), cfg), cfg),
            taa.init(scene, camera, cfg))


def _step(pipe, scene, static, state, camera, t, cfg):
    """Frame ``t`` of the scene posed at ``t``, through the pipeline and, with ``taa``, the
    temporal resolve."""
    posed = _posed(scene, t)
    if cfg.taa:
        return taa.step(pipe, posed, static, state, camera, t, cfg)
    return pipe.step(posed, static, state, camera, t, cfg)


OUTPUTS = ("all", "images")


def images_only(frame: Frame) -> Frame:
    """``frame`` less its counts and views: its image and, where it has one, the overflow
    count (which the image already depends on: an overflowed image is NaN)."""
    over = (frame.counts or {}).get("overflow")
    return Frame(frame.image, {} if over is None else {"overflow": over}, {})


def _program(pipe, static_cfg, mode, outputs, scene, static, cameras, traced, start):
    cfg = join_config(static_cfg, traced)
    keep = images_only if outputs == "images" else (lambda frame: frame)
    if mode == "frame":
        state = _init(pipe, scene, static, cameras, cfg)
        frame, _ = _step(pipe, scene, static, state, cameras, start, cfg)
        return keep(frame)
    _, skip = mode
    n = int(np.shape(jax.tree_util.tree_leaves(cameras)[0])[0])

    def body(state, xs):
        camera, t = xs
        frame, state = _step(pipe, scene, static, state, camera, t, cfg)
        return state, keep(frame)

    state = _init(pipe, scene, static, _first(cameras), cfg)
    ts = start + jnp.arange(n, dtype=jnp.int32)
    _, frames = jax.lax.scan(body, state, (cameras, ts))
    return jax.tree_util.tree_map(lambda a: a[skip:], frames) if skip else frames


_program_jit = jax.jit(_program, static_argnums=(0, 1, 2, 3))

# On a GPU XLA reads every loop condition and branch index back to the host before it goes on,
# unless its CUDA graphs hold the loops and branches too (conditional nodes). Forward and
# object space run faster so; DACS, TADS and the visibility buffer ran slower so when last
# measured (RESULTS.md, thirty-ninth and twelfth sessions). Other platforms ignore the option.
DEVICE_CONTROL_FLOW = ("forward", "object_space")
GRAPH_COMMANDS = "FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE"
_program_graphs_jit = jax.jit(_program, static_argnums=(0, 1, 2, 3),
                              compiler_options={"xla_gpu_enable_command_buffer": GRAPH_COMMANDS})


def program_jit(pipe):
    """The jitted program of ``pipe``: with its control flow in CUDA graphs for the pipelines of
    ``DEVICE_CONTROL_FLOW``."""
    return _program_graphs_jit if pipe.name in DEVICE_CONTROL_FLOW else _program_jit


def _run_program(pipe, fixed, args):
    """``pipe``'s program called on ``args``; inside another program's trace (jax takes
    compiler options on a top-level jit only) the plain one, under the outer program's
    options."""
    if _is_traced(*args):
        return _program_jit(*fixed, *args)
    try:
        return program_jit(pipe)(*fixed, *args)
    except ValueError as e:  # called inside a trace on closed-over, concrete arguments
        if "can only be passed to top-level" not in str(e):
            raise
        return _program_jit(*fixed, *args)


def unjitted(fixed) -> Callable:
    """The program of ``arguments``' static arguments, as a plain function of its dynamic
    ones: for tools that read or interpret its jaxpr (``jax.make_jaxpr``)."""
    return lambda *args: _program(*fixed, *args)


def cache_size() -> int:
    """Programs compiled so far in this process (tests: a camera move must not add one)."""
    return _program_jit._cache_size() + _program_graphs_jit._cache_size()


def clear_cache() -> None:
    """Drop every compiled program of this process (each holds host memory maps; a process
    that compiles many configs, like the parameter audit, runs out of them)."""
    _program_jit.clear_cache()
    _program_graphs_jit.clear_cache()


# ---------------------------------------------------------------- arguments and checks


def stack_cameras(cameras) -> Camera:
    """A Camera batched over a leading frame axis from a CameraPath, a batched Camera or a
    list of cameras (or of (camera, previous) pairs)."""
    if hasattr(cameras, "cameras"):  # a CameraPath
        return cameras.cameras
    if isinstance(cameras, (list, tuple)):
        cams = [c[0] if isinstance(c, tuple) else c for c in cameras]
        if not cams:
            raise ValueError("render_sequence: the camera path is empty")
        return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *cams)
    return cameras


def _mode(sequence: bool, warmup_frames: int, n_frames: int):
    if not sequence:
        return "frame"
    skip = int(warmup_frames)
    if skip < 0 or skip >= n_frames:
        raise ValueError(f"warmup_frames must be in [0, {n_frames}) for a path of {n_frames} "
                         f"frames, got {warmup_frames}")
    return ("sequence", skip)


def _is_traced(*trees) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(trees))


def check_overflow(pipe, cfg, frame: Frame) -> Frame:
    """Raise PipelineOverflow when any frame of ``frame`` (one or a sequence) overflowed."""
    over = (frame.counts or {}).get("overflow")
    if over is None or isinstance(over, jax.core.Tracer):
        return frame
    over = np.atleast_1d(np.asarray(over))
    bad = np.flatnonzero(over > 0)
    if bad.size:
        where = "" if over.size == 1 else f" in frame(s) {bad[:8].tolist()}"
        raise PipelineOverflow(f"{pipe.name}: {int(over[bad].sum())} overflow(s){where}: "
                               f"{cfg.overflow_hint()}")
    return frame


# ---------------------------------------------------------------- entry points


@dataclass(frozen=True)
class Prepared:
    """What a lowered program needs besides its compiled code: the pipeline's static data and
    the traced config values. Picklable (it crosses to the study's compile workers)."""

    static: Any
    traced: dict
    sequence: bool
    start: int = 0


def _arguments(pipe, scene, cameras, cfg, sequence: bool, warmup_frames: int, start=0,
               outputs: str = "all"):
    """(static jit arguments, dynamic arguments, Prepared) of ``pipe``'s program; host-side
    preparation happens here. ``start``: the frame index (animation clock) of the first frame;
    ``outputs``: one of OUTPUTS."""
    if outputs not in OUTPUTS:
        raise ValueError(f"outputs must be one of {', '.join(OUTPUTS)}, got {outputs!r}")
    if not _is_traced(scene, cameras):  # a compile may follow: room for its kernels
        memory_maps.release_if_crowded()
    if sequence:
        cameras = stack_cameras(cameras)
    n = int(np.shape(cameras.eye)[0]) if sequence else 1
    mode = _mode(sequence, warmup_frames, n)
    static = pipe.prepare(scene, cfg)
    static_cfg, traced = split_config(cfg)
    t0 = jnp.asarray(start, jnp.int32)
    return ((pipe, static_cfg, mode, outputs), (scene, static, cameras, traced, t0),
            Prepared(static, traced, sequence, start))


def render(pipe, scene, camera, cfg, *, t=0) -> Frame:
    """Frame ``t`` of ``pipe`` (the scene posed at ``t``; with TAA, its jitter phase) from its
    initial state, overflow-checked. ``t`` is traced: another frame does not recompile."""
    fixed, args, _ = _arguments(pipe, scene, camera, cfg, False, 0, t)
    frame = _run_program(pipe, fixed, args)
    return frame if _is_traced(scene, camera, t) else check_overflow(pipe, cfg, frame)


def render_sequence(pipe, scene, cameras, cfg, *, warmup_frames: int = 0, start=0) -> Frame:
    """Frames ``start``, ``start + 1``, ... of a camera path through ``pipe``'s steps, state
    carried, warm-up dropped."""
    fixed, args, _ = _arguments(pipe, scene, cameras, cfg, True, warmup_frames, start)
    frames = _run_program(pipe, fixed, args)
    return frames if _is_traced(*args) else check_overflow(pipe, cfg, frames)


def arguments(pipe, scene, cameras, cfg, *, sequence: bool = False, warmup_frames: int = 0,
              outputs: str = "all"):
    """(static jit arguments, dynamic arguments, Prepared) of ``pipe``'s program, host-side
    preparation done and nothing traced: what identifies a compiled program without lowering
    it (the study's executable store keys on these). ``outputs``: one of OUTPUTS."""
    return _arguments(pipe, scene, cameras, cfg, sequence, warmup_frames, outputs=outputs)


def lower_arguments(fixed, args):
    """The jax Lowered program of ``arguments``' static and dynamic arguments."""
    return program_jit(fixed[0]).lower(*fixed, *args)


def lower(pipe, scene, cameras, cfg, *, sequence: bool = False, warmup_frames: int = 0,
          outputs: str = "all"):
    """(jax Lowered program, Prepared) for ``pipe`` on this scene and camera (a single camera,
    or a path when ``sequence``), returning ``outputs`` (one of OUTPUTS)."""
    fixed, args, prepared = _arguments(pipe, scene, cameras, cfg, sequence, warmup_frames,
                                       outputs=outputs)
    return lower_arguments(fixed, args), prepared


def bind(pipe, cfg, compiled, prepared: Prepared) -> Callable:
    """``call(scene, cameras, t=None) -> Frame``: the compiled program with its prepared
    arguments, overflow-checked like ``render``."""

    def call(scene, cameras, t=None, traced=None):
        """``t``: the frame index of the (first) frame; default: the one it was lowered for.
        ``traced``: other values of the config's TRACED_FIELDS (``split_config``'s second
        half of a config that differs from ``cfg`` in them only); default: ``cfg``'s."""
        if prepared.sequence:
            cameras = stack_cameras(cameras)
        start = prepared.start if t is None else t
        values = prepared.traced if traced is None else traced
        frame = compiled(scene, prepared.static, cameras, values,
                         jnp.asarray(start, jnp.int32))
        return check_overflow(pipe, cfg, frame)

    return call


def compile(pipe, scene, cameras, cfg, *, sequence: bool = False, warmup_frames: int = 0,
            outputs: str = "all") -> tuple[Callable, float]:
    """Ahead of time: (``call(scene, cameras) -> Frame``, compile ms including preparation);
    ``outputs="images"``: the Frames hold the images and the overflow count alone."""
    t0 = time.perf_counter()
    lowered, prepared = lower(pipe, scene, cameras, cfg, sequence=sequence,
                              warmup_frames=warmup_frames, outputs=outputs)
    compiled = lowered.compile()
    return bind(pipe, cfg, compiled, prepared), (time.perf_counter() - t0) * 1e3


__all__ = ["OUTPUTS", "PipelineOverflow", "Prepared", "arguments", "bind", "cache_size",
           "check_overflow", "clear_cache", "compile", "images_only", "join_config", "lower",
           "lower_arguments", "render", "render_sequence", "split_config", "stack_cameras"]
