"""Triangle ids of two rasterizers compared pixel by pixel, ties told apart (for
bench_peers.py).

Raw agreement; agreement with depth ties excluded (a differing pixel where the other
rasterizer's triangle has, at the pixel centre, the same window depth as jaxrender's within
TIE_EPS: both answers are right); agreement with edge ties excluded as well (the centre within
one snapping step, 1/256 px, of an edge of either triangle, where the two rasterizers' vertex
snapping decides); and agreement on pixels away from triangle edges (the pixel and its 4
neighbours share one id in both images).
"""

from __future__ import annotations

import numpy as np

from jaxrender.raster.setup import SUBPIXEL_BITS

TIE_EPS = 1e-6
EDGE_EPS = 1.0 / (1 << SUBPIXEL_BITS)  # px: one step of the snapping grid


def window_coordinates(clip, width, height):
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
    x, y, z, w = window_coordinates(clip, width, height)
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


def interior(ids):
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
    inside = interior(ours) & interior(theirs)
    n = ours.size
    return {
        "ids_agree": float(np.mean(same)),
        "ids_agree_excl_ties": float(np.sum(same) / max(n - ties, 1)),
        "ids_agree_excl_all_ties": float(np.sum(same) / max(n - ties - edge_ties, 1)),
        "ids_agree_interior": float(np.mean(same[inside])) if inside.any() else float("nan"),
        "interior_fraction": float(np.mean(inside)),
        "differing_pixels": int(n - np.sum(same)),
        "depth_ties": ties,
        "edge_ties": edge_ties,
        "coverage_only_diffs": int(np.sum(~both)),
    }
