"""Helpers for raster tests: fixed padded sizes so that one compile serves many scenes."""

import numpy as np

N_VERTS, N_FACES = 1536, 512  # every test scene is padded to these sizes


def pad(verts: np.ndarray, faces: np.ndarray, n_verts=N_VERTS, n_faces=N_FACES):
    """Pad with unused vertices and degenerate faces (all corners on vertex 0: zero area, so
    they can never produce a fragment)."""
    assert len(verts) <= n_verts and len(faces) <= n_faces, (len(verts), len(faces))
    v = np.zeros((n_verts, verts.shape[1]), np.float32)
    v[: len(verts)] = verts
    if verts.shape[1] == 4:
        v[len(verts):, 3] = 1.0
    f = np.zeros((n_faces, 3), np.int32)
    f[: len(faces)] = faces
    return v, f


def gl_clip(p_cam: np.ndarray, *, fov_y_deg=90.0, aspect=1.0, near=0.1, far=100.0) -> np.ndarray:
    """GL perspective projection of camera-space points, in float64 then rounded once."""
    f = 1.0 / np.tan(np.deg2rad(fov_y_deg) / 2)
    x, y, z = p_cam[:, 0], p_cam[:, 1], p_cam[:, 2]
    zc = (far + near) / (near - far) * z + 2 * far * near / (near - far)
    return np.stack([f / aspect * x, f * y, zc, -z], 1).astype(np.float32)
