"""Forward's transparent geometry, drawn after its opaque geometry as engines draw it: the
opaque triangles alone in its draw list, then the transparent triangles' fragment list tested
against its final opaque depth, shaded and blended by the shared transparent pass
(``transparency.blend_fragments``)."""

from __future__ import annotations

import jax

from jaxrender.pipelines.transparency import (blend_fragments, check_settings, in_front,
                                              refuse_transparency, transparent_fragments)
from jaxrender.pipelines.visibility import opaque_faces


def forward_faces(scene, cfg):
    """The faces of forward's draw list: the opaque ones (the blended ones made degenerate, so
    ids stay the scene's), or all of them for a scene without transparency."""
    check_settings(scene, cfg)
    if scene.effects.transparency and (cfg.msaa > 1 or cfg.shade_helpers):
        refuse_transparency(scene, "forward with msaa > 1 or shade_helpers")
    return opaque_faces(scene)


def forward_transparent(scene, camera, clip, image, z_final, cfg):
    """The transparent triangles' fragments in front of forward's final opaque depth
    (``z_final`` float32[P], +inf where none) shaded and blended over its opaque image.
    Returns (image, counts as ``blend_fragments`` gives them, the fragment list, bool[F] its
    fragments in front), or (image, None, None, None) for a scene without transparency."""
    if not scene.effects.transparency:
        return image, None, None, None
    with jax.named_scope("transparent"):
        with jax.named_scope("fragments"):
            fr = transparent_fragments(scene, clip, cfg)
        image, counts = blend_fragments(scene, camera, clip, fr, image, z_final, cfg)
    front = in_front(fr.valid, fr.pixel, fr.depth, z_final, z_final.shape[0])
    return image, counts, fr, front


__all__ = ["forward_faces", "forward_transparent"]
