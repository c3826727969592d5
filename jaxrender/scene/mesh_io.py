"""Mesh files (OBJ, PLY, glTF/GLB, ...) through trimesh: geometry, UVs, normals, base colour
textures and materials, with the file's scene-graph transforms applied."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jaxrender.scene.materials import Material
from jaxrender.scene.mesh import MeshPart
from jaxrender.scene.textures import as_rgba


def _colour(value, default):
    if value is None:
        return default
    c = np.asarray(value, np.float64).ravel()
    if np.asarray(value).dtype == np.uint8:
        c = c / 255.0
    return tuple(float(x) for x in c[:3]) if c.size >= 3 else default


def load_mesh_file(path: str | Path, materials: list[Material], textures: list[np.ndarray]
                   ) -> list[MeshPart]:
    """Parts of one mesh file, in the file's own world space. New materials and textures are
    appended to ``materials`` / ``textures``; each part's ``material`` indexes the list."""
    import trimesh
    from trimesh.visual.material import PBRMaterial

    loaded = trimesh.load(str(path), force="scene", process=False)
    parts, seen = [], {}
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        geom = loaded.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        vis = geom.visual
        uvs, mat_key = None, None
        if vis is not None and vis.kind == "texture":
            if vis.uv is not None and len(vis.uv) == len(geom.vertices):
                uvs = np.asarray(vis.uv, np.float64)
            mat_key = id(vis.material)
        if mat_key is not None and mat_key in seen:
            mat_index = seen[mat_key]
        else:
            mat_index = len(materials)
            materials.append(_material_of(geom, len(materials), textures, PBRMaterial))
            if mat_key is not None:
                seen[mat_key] = mat_index
        part = MeshPart(
            positions=np.asarray(geom.vertices, np.float64),
            faces=np.asarray(geom.faces, np.int64),
            normals=np.asarray(geom.vertex_normals, np.float64),
            uvs=uvs, material=mat_index, name=str(node),
        )
        parts.append(part.transformed(np.asarray(transform, np.float64)))
    if not parts:
        raise ValueError(f"{path}: no triangle meshes in the file")
    return parts


def _material_of(geom, index, textures, PBRMaterial) -> Material:
    vis = geom.visual
    name = f"{Path(str(geom.metadata.get('file_name', 'mesh'))).stem}_{index}"
    if vis is None or vis.kind != "texture" or vis.material is None:
        if vis is not None and vis.kind in ("vertex", "face"):
            c = np.asarray(vis.main_color, np.float64)[:3] / 255.0
            return Material(name, albedo=tuple(c))
        return Material(name)
    mat = vis.material
    image, alpha_mode, cutoff = None, None, 0.5
    if isinstance(mat, PBRMaterial):
        albedo = _colour(mat.baseColorFactor, (1.0, 1.0, 1.0))
        image = mat.baseColorTexture
        alpha_mode, cutoff = mat.alphaMode, (mat.alphaCutoff if mat.alphaCutoff is not None else 0.5)
        rough = float(mat.roughnessFactor) if mat.roughnessFactor is not None else 1.0
        metal = float(mat.metallicFactor) if mat.metallicFactor is not None else 0.0
        spec = tuple(0.04 * (1 - metal) + a * metal for a in albedo)
        kwargs = dict(brdf="ggx", roughness=max(rough, 1e-3), specular=spec,
                      emissive=_colour(mat.emissiveFactor, (0.0, 0.0, 0.0)))
    else:
        albedo = _colour(getattr(mat, "diffuse", None), (0.8, 0.8, 0.8))
        image = getattr(mat, "image", None)
        kwargs = {}
    tex = -1
    if image is not None:
        tex = len(textures)
        textures.append(as_rgba(np.asarray(image.convert("RGBA")), srgb=True))
        albedo = (1.0, 1.0, 1.0) if not isinstance(mat, PBRMaterial) else albedo
    return Material(name, albedo=albedo, texture=tex, alpha_tested=alpha_mode == "MASK",
                    alpha_cutoff=float(cutoff), **kwargs)
