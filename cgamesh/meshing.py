"""Meshing evolved circle surfaces by TRS-rotor stepping (paper section 11).

The first ring is the unit circle's points carried to C(0) by the TRS rotor Z_0 = T D R_0;
each following ring is the previous one carried by the TRS rotor from C(t_k) to C(t_{k+1}).
Translation and dilation of that rotor are fixed by the two circles' centres and radii; its
rotation R_k is the smallest rotation between their planes, and only the rotations
accumulate (``transported_frames``). So ring k's points are

    x_kj = c_k + r_k (cos theta_j u_k + sin theta_j v_k),   u_k = (R_k ... R_1 R_0) e1,

which is the sandwich Z X ~Z of the composed rotors evaluated as the similarity it is.
Centre and radius are read from C(t_k) itself at every ring, so no error accumulates in
them, and u_k is re-orthogonalised against the exact plane: vertices stay on their circles
to rounding at any step count. The (t, theta) grid is triangulated directly; its seam
column and, for closed loops, its last ring repeat the first bit for bit.
"""

from __future__ import annotations

import numpy as np

from cgamesh import normals as normal_field
from cgamesh import uv as uv_map
from cgamesh.algebra import rotors
from cgamesh.mesh import SurfaceMesh
from cgamesh.surface import CircleRings, EvolvedSurface

E1 = np.array([1.0, 0.0, 0.0])
E3 = np.array([0.0, 0.0, 1.0])
# A ring moving slower than this fraction of its radius per unit alpha is stationary (e.g. a
# Kochanek-Bartels control with tension 1): its normals come from just past it.
STATIONARY_FRACTION = 1e-9
STATIONARY_OFFSET = 1e-6
# Triangles next to vertices where the normal field vanishes are checked for zero area.
NEAR_ZERO_FRACTION = 1e-6


def transported_frames(normal: np.ndarray, closed: bool, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes u, v (K, 3) of each ring, carried from ring to ring by TRS rotations.

    For a closed loop, the rotation accumulated around the loop (its holonomy) is spread
    evenly along it, so the last ring's axes equal the first's.
    """
    steps = np.concatenate(
        [rotors.rotation_between(E3, normal[:1]), rotors.rotation_between(normal[:-1], normal[1:])]
    )
    u = rotors.apply_to_euclidean(rotors.prefix_products(steps), np.broadcast_to(E1, normal.shape))
    u -= np.einsum("ki,ki->k", u, normal)[:, None] * normal
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normal, u)
    if closed:
        twist = np.arctan2(np.dot(np.cross(u[0], u[-1]), normal[0]), np.dot(u[0], u[-1]))
        angle = -twist * (t - t[0]) / (t[-1] - t[0])
        u = np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * v
        v = np.cross(normal, u)
    return u, v


def _ring_normal_coefficients(rings: CircleRings, u: np.ndarray, v: np.ndarray):
    """(zeta, rho) coefficients (K, 7, 2), velocity scale (K,), and sample points (K, 7, 3)."""
    points, radial = normal_field.sample_points(rings.centre, rings.radius, u, v)
    velocity = rings.velocity(points)
    coefficients = normal_field.normal_coefficients(velocity, radial, rings.normal)
    return coefficients, np.linalg.norm(velocity, axis=-1).max(axis=1), points


def _fix_stationary_rings(surface, t, rings, u, coefficients, speed):
    """Replace the normal coefficients of rings that do not move by those just past them."""
    stationary = speed <= STATIONARY_FRACTION * rings.radius
    if not np.any(stationary):
        return coefficients, speed
    end = surface.segment_count
    nearby_t = np.where(t[stationary] + STATIONARY_OFFSET <= end, t[stationary] + STATIONARY_OFFSET,
                        t[stationary] - STATIONARY_OFFSET)
    nearby = CircleRings.from_projection(surface.sample(nearby_t), surface.frame)
    nearby_u = u[stationary] - np.einsum("ki,ki->k", u[stationary], nearby.normal)[:, None] * nearby.normal
    nearby_u /= np.linalg.norm(nearby_u, axis=1, keepdims=True)
    nearby_coefficients, nearby_speed, _ = _ring_normal_coefficients(
        nearby, nearby_u, np.cross(nearby.normal, nearby_u)
    )
    coefficients = coefficients.copy()
    speed = speed.copy()
    coefficients[stationary] = nearby_coefficients
    speed[stationary] = nearby_speed
    return coefficients, speed


def grid_faces(rings: int, columns: int, signs: np.ndarray) -> np.ndarray:
    """Triangles (2 (rings-1)(columns-1), 3) of a (rings, columns) vertex grid.

    Quad (k, j) splits into (k,j)(k,j+1)(k+1,j) and (k,j+1)(k+1,j+1)(k+1,j), both wound like
    d/dtheta x d/dt. signs (rings, columns): where the normal field is flipped (the sum of a
    triangle's three vertex signs is negative) the triangle's winding is reversed too.
    """
    k, j = np.meshgrid(np.arange(rings - 1), np.arange(columns - 1), indexing="ij")
    a = (k * columns + j).ravel()
    b, c, d = a + 1, a + columns, a + columns + 1
    faces = np.empty((2 * a.size, 3), dtype=np.int64)
    faces[0::2] = np.stack([a, b, c], axis=1)
    faces[1::2] = np.stack([b, d, c], axis=1)
    flat = signs.ravel()
    flipped = flat[faces].sum(axis=1) < 0.0
    faces[flipped] = faces[flipped][:, [0, 2, 1]]
    return faces


def drop_zero_area(positions: np.ndarray, faces: np.ndarray, suspects: np.ndarray) -> np.ndarray:
    """Remove triangles of zero area among those touching suspect vertices (V,) bool."""
    candidates = np.flatnonzero(suspects[faces].any(axis=1))
    if candidates.size == 0:
        return faces
    p = positions[faces[candidates]]
    edge_a, edge_b = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area2 = np.linalg.norm(np.cross(edge_a, edge_b), axis=1)
    longest = np.maximum(np.einsum("ti,ti->t", edge_a, edge_a), np.einsum("ti,ti->t", edge_b, edge_b))
    degenerate = area2 <= 1e-12 * longest
    return np.delete(faces, candidates[degenerate], axis=0)


def mesh_circle_surface(surface: EvolvedSurface, around: int, along: int, caps: bool = False,
                        closed: bool = False) -> SurfaceMesh:
    """Triangulate an evolved circle surface on ``along`` rings of ``around`` vertices.

    Each ring carries around + 1 vertices (the UV seam column repeats the first one).
    """
    surface.check_projection_exists()
    t = np.linspace(0.0, surface.segment_count, along)
    rings = CircleRings.from_projection(surface.sample(t), surface.frame)
    u, v = transported_frames(rings.normal, closed, t)

    coefficients, speed, ring_samples = _ring_normal_coefficients(rings, u, v)
    coefficients, speed = _fix_stationary_rings(surface, t, rings, u, coefficients, speed)

    theta = 2.0 * np.pi * np.arange(around + 1) / around
    radial = np.cos(theta)[None, :, None] * u[:, None, :] + np.sin(theta)[None, :, None] * v[:, None, :]
    positions = rings.centre[:, None, :] + rings.radius[:, None, None] * radial

    zeta_rho = normal_field.evaluate(coefficients, theta, speed)
    size = np.hypot(zeta_rho[..., 0], zeta_rho[..., 1])
    signs = normal_field.continuous_signs(zeta_rho)
    # Outward on the whole: sum over vertices of n . (x - centre) = sum s zeta r / |.| > 0.
    if np.sum(signs * zeta_rho[..., 0] / size * rings.radius[:, None]) < 0.0:
        signs = -signs
    scaled = zeta_rho * (signs / size)[..., None]
    normals = scaled[..., 0:1] * radial - scaled[..., 1:2] * rings.normal[:, None, :]

    positions[:, -1] = positions[:, 0]
    normals[:, -1] = normals[:, 0]
    if closed:
        positions[-1] = positions[0]
        normals[-1] = normals[0]

    columns = around + 1
    faces = grid_faces(along, columns, signs)
    positions = positions.reshape(-1, 3)
    normals = normals.reshape(-1, 3)
    suspects = (size <= NEAR_ZERO_FRACTION * speed[:, None]).ravel()
    faces = drop_zero_area(positions, faces, suspects)
    uvs = uv_map.grid_uvs(uv_map.along_coordinates(ring_samples), columns)

    if caps:
        # Each cap faces away from the tube: against the direction its ring moves in.
        leaving = np.sign(coefficients[[0, -1], 0, 0]) * np.array([-1.0, 1.0])
        leaving[leaving == 0.0] = np.array([-1.0, 1.0])[leaving == 0.0]
        for ring, facing in zip((0, along - 1), leaving):
            rim = positions[ring * columns: ring * columns + around]
            positions, normals, uvs, faces = _add_cap(
                positions, normals, uvs, faces, rings, ring, rim, theta[:-1], facing
            )
    return SurfaceMesh(name=surface.name, positions=positions, normals=normals, uvs=uvs, faces=faces)


def _add_cap(positions, normals, uvs, faces, rings, ring, rim, theta, facing):
    """Append a flat disc closing ring ``ring``; facing = +1 along the circle's normal, -1 against."""
    around = len(rim)
    start = len(positions)
    cap_normal = facing * rings.normal[ring]
    cap_positions = np.vstack([rim, rings.centre[ring][None]])
    j = np.arange(around)
    centre = start + around
    fan = np.stack([np.full(around, centre), start + j, start + (j + 1) % around], axis=1)
    if facing < 0:  # rim points run counter-clockwise about the circle's normal
        fan = fan[:, [0, 2, 1]]
    return (
        np.vstack([positions, cap_positions]),
        np.vstack([normals, np.broadcast_to(cap_normal, cap_positions.shape)]),
        np.vstack([uvs, uv_map.disc_uvs(theta)]),
        np.vstack([faces, fan]),
    )
