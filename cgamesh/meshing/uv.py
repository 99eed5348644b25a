"""Texture coordinates: natural UVs in the (alpha, n) parameter plane, and the scene's uv modes.

The meshers give u around each circle (or across a ribbon) in [0, 1] and v along the surface
in [0, 1] in proportion to arc length, measured between consecutive rings, so a checker
texture keeps its cells along a tube whose rings are unevenly spaced in alpha. The scene's
``uv`` mode then rescales them for even texel density (natural), zeroes them (none) or
replaces them by an xatlas atlas (``apply_uv_modes``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cgamesh.meshing.mesh import SurfaceMesh


def along_coordinates(ring_samples: np.ndarray) -> np.ndarray:
    """v (..., K) from points (..., K, S, 3) sampled at the same S places on each ring.

    The step between rings is the mean distance the S samples travel; v is the
    running sum of steps, normalised to end at 1.
    """
    return normalised(along_lengths(ring_samples))


def along_lengths(ring_samples: np.ndarray) -> np.ndarray:
    """Arc length (..., K) travelled from the first ring: the running sum of the mean distance the
    S samples (..., K, S, 3) move between consecutive rings."""
    steps = np.linalg.norm(np.diff(ring_samples, axis=-3), axis=-1).mean(axis=-1)
    return np.concatenate([np.zeros(steps.shape[:-1] + (1,)), np.cumsum(steps, axis=-1)], axis=-1)


def normalised(travelled: np.ndarray) -> np.ndarray:
    """``travelled`` (..., K) divided by its last value (evenly spaced in [0, 1] where that is 0)."""
    last = travelled[..., -1:]
    moved = last > 0.0
    if moved.all():
        return travelled / last
    return np.where(moved, travelled / np.where(moved, last, 1.0), np.linspace(0.0, 1.0, travelled.shape[-1]))


def mean_along(values: np.ndarray, travelled: np.ndarray) -> float:
    """Mean of per-ring ``values`` (K,) over the length ``travelled`` (K,) (trapezoid rule);
    the plain mean when the rings do not move."""
    if travelled[-1] > 0.0:
        return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(travelled)) / travelled[-1])
    return float(np.mean(values))


def grid_uvs(v: np.ndarray, columns: int) -> np.ndarray:
    """UVs (..., K * columns, 2) of (..., K, columns) grids: u = j / (columns - 1), v (..., K) per ring."""
    u = np.linspace(0.0, 1.0, columns)
    return np.stack(np.broadcast_arrays(u, v[..., None]), axis=-1).reshape(v.shape[:-1] + (-1, 2))


def disc_uvs(theta: np.ndarray, mirrored: bool = False) -> np.ndarray:
    """UVs (M + 1, 2) of a disc: its rim at angles theta (M,), then its centre; ``mirrored``
    runs u the other way (a disc seen from the other side keeps counter-clockwise UVs)."""
    u = np.cos(theta) * (-1.0 if mirrored else 1.0)
    rim = np.stack([0.5 + 0.5 * u, 0.5 + 0.5 * np.sin(theta)], axis=1)
    return np.vstack([rim, [[0.5, 0.5]]])


# --- the scene's uv modes: natural (scaled), none, xatlas --------------------------------------


def apply_uv_modes(meshes: list[SurfaceMesh], modes: list[tuple[str, float | None]]) -> list[SurfaceMesh]:
    """Each mesh with the UVs its surface asks for; ``modes`` [(uv, uv_scale)] in mesh order.

    natural: u' = u * Lu / s, v' = v * Lv / s, where (Lu, Lv) are the file-unit lengths one unit
        of the meshers' u and v spans (``SurfaceMesh.uv_lengths``: a tube's circumference averaged
        along its length and its length along; a cap's diameter, both ways; measured from the
        triangles when a mesher does not state them) and s is ``uv_scale`` (file units per texture
        repeat) or, by default, the largest of u * Lu and v * Lv over the mesh: the surface fills
        the unit square along its longer side, with square texels everywhere.
    none: every UV is (0, 0) (the scene format still gives every vertex a TEXCOORD_0 / st);
        tangents are then refused, having no texture directions to follow.
    xatlas: the surfaces that ask for it are unwrapped by xatlas into ONE atlas in [0, 1]^2
        (see ``xatlas_atlas``); their vertices are split along chart seams.
    """
    out = list(meshes)
    for i, (mode, scale) in enumerate(modes):
        if mode == "natural":
            out[i] = natural(meshes[i], scale)
        elif mode == "none":
            out[i] = replace(meshes[i], uvs=np.zeros_like(meshes[i].uvs), tangents=None, uv_lengths=None)
        elif mode != "xatlas":
            raise ValueError(f"unknown uv mode {mode!r}")
    atlas = [i for i, (mode, _) in enumerate(modes) if mode == "xatlas"]
    if atlas:
        for i, mesh in zip(atlas, xatlas_atlas([meshes[i] for i in atlas])):
            out[i] = mesh
    return out


def natural(mesh: SurfaceMesh, scale: float | None = None) -> SurfaceMesh:
    """Natural UVs with even texel density (see ``apply_uv_modes``)."""
    world = _natural_lengths(mesh)
    if scale is None:
        scale = float(world.max())
    if not scale > 0.0:
        return mesh
    return replace(mesh, uvs=world / scale)


def natural_extent(mesh: SurfaceMesh) -> float:
    """The largest natural UV in file units (u * Lu or v * Lv over the mesh): natural UVs with
    ``uv_scale`` s reach this over s."""
    return float(_natural_lengths(mesh).max(initial=0.0))


def _natural_lengths(mesh: SurfaceMesh) -> np.ndarray:
    lengths = mesh.uv_lengths if mesh.uv_lengths is not None else measured_lengths(mesh)
    return mesh.uvs * lengths


def measured_lengths(mesh: SurfaceMesh) -> np.ndarray:
    """(1, 2) file-unit lengths of one unit of u and of v: the area-weighted means of |dx/du| and
    |dx/dv| over the triangles whose UVs have area."""
    d_u, d_v, area, valid = _uv_jacobians(mesh.positions, mesh.uvs, mesh.faces)
    weight = area * valid
    if weight.sum() <= 0.0:
        return np.ones((1, 2))
    return np.array([[np.linalg.norm(d_u, axis=1) @ weight, np.linalg.norm(d_v, axis=1) @ weight]]) / weight.sum()


def _uv_jacobians(positions, uvs, faces):
    """Per triangle: dx/du (F, 3), dx/dv (F, 3), 3-d area (F,), and whether its UV area is > 0."""
    p = positions[faces]
    t = uvs[faces]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    a1, a2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    det = a1[:, 0] * a2[:, 1] - a1[:, 1] * a2[:, 0]
    valid = np.abs(det) > 1e-14 * np.maximum(np.abs(a1).max(axis=1) * np.abs(a2).max(axis=1), 1e-300)
    inv = np.where(valid, 1.0 / np.where(valid, det, 1.0), 0.0)[:, None]
    d_u = (e1 * a2[:, 1:2] - e2 * a1[:, 1:2]) * inv
    d_v = (e2 * a1[:, 0:1] - e1 * a2[:, 0:1]) * inv
    area = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)
    return d_u, d_v, area, valid


def tangents_of(mesh: SurfaceMesh) -> np.ndarray:
    """(V, 4) glTF tangents: the mesher's analytic ones, or else from the UV gradients.

    From UVs: at each vertex the area-weighted sum of its triangles' unit dx/du, made orthogonal
    to the normal; w = +1 when cross(normal, tangent) has the direction of dx/dv there, else -1.
    Raises ValueError when the mesh has no UV layout at all (uv: none).
    """
    if mesh.tangents is not None:
        return mesh.tangents
    d_u, d_v, area, valid = _uv_jacobians(mesh.positions, mesh.uvs, mesh.faces)
    if not valid.any():
        raise ValueError(f"surface {mesh.name!r} has no UV layout (uv: none), so tangents have no direction")
    weight = (area * valid)[:, None]
    t_face = d_u / np.maximum(np.linalg.norm(d_u, axis=1, keepdims=True), 1e-300) * weight
    b_face = d_v / np.maximum(np.linalg.norm(d_v, axis=1, keepdims=True), 1e-300) * weight
    v = mesh.vertex_count
    t_sum, b_sum = np.zeros((v, 3)), np.zeros((v, 3))
    for corner in range(3):
        np.add.at(t_sum, mesh.faces[:, corner], t_face)
        np.add.at(b_sum, mesh.faces[:, corner], b_face)
    n = mesh.normals
    t = t_sum - np.einsum("ij,ij->i", t_sum, n)[:, None] * n
    length = np.linalg.norm(t, axis=1)
    lost = ~(length > 1e-12 * np.maximum(np.linalg.norm(t_sum, axis=1), 1e-300))
    if lost.any():  # no usable UV direction at the vertex: any unit vector orthogonal to n
        helper = np.where(np.abs(n[lost, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        t[lost] = np.cross(n[lost], helper)
        length[lost] = np.linalg.norm(t[lost], axis=1)
    t /= length[:, None]
    w = np.where(np.einsum("ij,ij->i", np.cross(n, t), b_sum) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1)


def xatlas_atlas(meshes: list[SurfaceMesh], padding: int = 2) -> list[SurfaceMesh]:
    """Unwrap ``meshes`` into one shared atlas in [0, 1]^2 with xatlas; vertices are split at seams.

    Two passes: xatlas cuts charts and parameterises them (LSCM can return a chart mirrored:
    such charts are mirrored back, so no triangle is flipped); then the fixed charts of every
    mesh are packed together, without rotations (a rotation to an axis can swap u and v, a
    mirror). Positions, normals and welds follow the vertices through both passes; the
    mesher's tangents no longer follow u and are dropped (``tangents_of`` derives new ones).
    """
    from cgamesh.optional import require

    xatlas = require("xatlas", "xatlas", "uv: xatlas")
    charts = xatlas.Atlas()
    for mesh in meshes:
        charts.add_mesh(np.ascontiguousarray(mesh.positions, dtype=np.float32),
                        np.ascontiguousarray(mesh.faces, dtype=np.uint32),
                        np.ascontiguousarray(mesh.normals, dtype=np.float32))
    charts.generate()
    packer, first_pass = xatlas.Atlas(), []
    for i in range(len(meshes)):
        vmapping, indices, uvs = charts[i]
        uvs = uvs.astype(np.float64)
        area = _signed_uv_area(uvs, indices)
        for c in range(charts.get_mesh_chart_count(i)):
            chart_faces = np.asarray(charts.get_mesh_chart(i, c).faces, dtype=np.int64)
            if area[chart_faces].sum() < 0.0:
                uvs[np.unique(indices[chart_faces]), 0] *= -1.0
        first_pass.append(vmapping.astype(np.int64))
        packer.add_uv_mesh(uvs.astype(np.float32), indices.astype(np.uint32))
    options = xatlas.PackOptions()
    options.padding = padding
    options.rotate_charts = False
    packer.generate(pack_options=options)
    out = []
    for i, mesh in enumerate(meshes):
        vmapping, indices, uvs = packer[i]
        source = first_pass[i][vmapping.astype(np.int64)]  # output vertex -> input vertex
        canonical = (mesh.weld if mesh.weld is not None else np.arange(mesh.vertex_count))[source]
        _, first, inverse = np.unique(canonical, return_index=True, return_inverse=True)
        out.append(replace(
            mesh,
            positions=mesh.positions[source],
            normals=mesh.normals[source],
            uvs=uvs.astype(np.float64),
            faces=indices.astype(np.int32).reshape(-1, 3),
            tangents=None,
            uv_lengths=None,
            weld=first[inverse.ravel()],
            # per-vertex channels follow their vertices into the split
            colors=None if mesh.colors is None else np.asarray(mesh.colors)[source],
            attributes=None if mesh.attributes is None else {
                name: np.asarray(values)[source] for name, values in mesh.attributes.items()},
        ))
    return out


def _signed_uv_area(uvs: np.ndarray, faces: np.ndarray) -> np.ndarray:
    a1 = uvs[faces[:, 1]] - uvs[faces[:, 0]]
    a2 = uvs[faces[:, 2]] - uvs[faces[:, 0]]
    return 0.5 * (a1[:, 0] * a2[:, 1] - a1[:, 1] * a2[:, 0])
