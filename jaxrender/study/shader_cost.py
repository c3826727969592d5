"""Shader cost as a study axis: the ``shader_cost`` key of a pipeline entry's ``params`` or
``sweep``.

The unit is one extra light layer (``Effects.shader_cost``): at cost c, ``shade()`` evaluates
every light 1 + c times per shaded point (each layer with the shading normal nudged by less than
1e-3 rad, averaged), so one shaded point costs 1 + c layer evaluations and the image barely
changes. The key sets the scene's shader cost for that variant only; without it a variant
renders with the scene's own (0 for the built-in scenes). Every variant's rows carry
``shader_cost`` and ``shading_work = shade_invocations x (1 + shader_cost)``: the layer
evaluations its frame ran, the x axis of the time fits (``time_fit``). Helper lanes (forward's 2x2 quads) run the shader
too but are not invocations, so they show in forward's slope per unit of work, not in its work.

The reference renders each scene with the scene's own shader: it is shared by every variant,
and the layers change an image by far less than any pipeline's error.
"""

from __future__ import annotations

KEY = "shader_cost"
WORK = "shading_work"
UNIT = "layer evaluations (one shaded point at shader cost c is 1 + c)"


def split(params: dict) -> tuple[dict, int | None]:
    """(the pipeline's own parameters, the variant's shader cost or None for the scene's)."""
    rest = {k: v for k, v in params.items() if k != KEY}
    return rest, params.get(KEY)


def shading_work(invocations, cost: int):
    """Layer evaluations of ``invocations`` shaded points at shader cost ``cost``."""
    return invocations * (1 + int(cost))
