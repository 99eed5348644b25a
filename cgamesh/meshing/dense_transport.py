"""Transported frames of densely sampled circle normals, for the tolerance plan's bounds.

The plan bounds d2x/dt2 in a frame carried along the samples by the smallest rotation between
consecutive normals (docs/tolerance.md, "A and B for circles"): the same rotations as
``cgamesh.meshing.circles.transported_frames`` (which the mesher uses, as rotors of the
algebra), composed here as unit quaternions: four numbers a rotation instead of a multivector,
so the thousands of samples of a plan are carried in a fraction of the time. The result agrees
with the mesher's frames to rounding; the bound needs only a transported frame, and the
mesher's own frames are bounded relative to it by their spin (the plan's psi).
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.objects import perpendicular_unit


def _prefix_products(steps: np.ndarray) -> np.ndarray:
    """Running Hamilton products (K, 4) q_k ... q_1 q_0 of quaternions steps (K, 4) as (w, x, y, z),
    by a log-depth scan (each pass multiplies every entry by the one ``shift`` before it), on the
    four components as separate contiguous rows: no stacking or concatenating per pass."""
    w, x, y, z = (np.ascontiguousarray(component) for component in steps.T)
    shift = 1
    while shift < len(w):
        pw, px, py, pz = w[shift:], x[shift:], y[shift:], z[shift:]
        qw, qx, qy, qz = w[:-shift], x[:-shift], y[:-shift], z[:-shift]
        product = (pw * qw - px * qx - py * qy - pz * qz,
                   pw * qx + px * qw + py * qz - pz * qy,
                   pw * qy - px * qz + py * qw + pz * qx,
                   pw * qz + px * qy - py * qx + pz * qw)
        for row, value in zip((w, x, y, z), product):
            row[shift:] = value
        shift *= 2
    return np.stack([w, x, y, z], axis=-1)


def _between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotations taking unit vectors a to b (K, 3), as unit quaternions (K, 4); a half
    turn about a perpendicular axis where b = -a."""
    q = np.concatenate([1.0 + np.sum(a * b, axis=-1, keepdims=True), np.cross(a, b)], axis=-1)
    norm = np.linalg.norm(q, axis=-1)
    opposite = norm < 1e-8
    if np.any(opposite):
        q[opposite] = np.concatenate([np.zeros((int(opposite.sum()), 1)), perpendicular_unit(a[opposite])], axis=-1)
        norm[opposite] = 1.0
    return q / norm[:, None]


def transported_axes(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes u, v (K, 3) of unit normals (K, 3), e1 carried from e3 to the first
    normal and then from sample to sample by the smallest rotations (a log-depth scan)."""
    steps = np.concatenate([_between(np.array([[0.0, 0.0, 1.0]]), normal[:1]), _between(normal[:-1], normal[1:])])
    acc = _prefix_products(steps)
    acc /= np.linalg.norm(acc, axis=-1, keepdims=True)
    w, axis = acc[:, :1], acc[:, 1:]
    e1 = np.broadcast_to(np.array([1.0, 0.0, 0.0]), axis.shape)
    turned = np.cross(axis, e1)
    u = e1 + 2.0 * w * turned + 2.0 * np.cross(axis, turned)
    u -= np.sum(u * normal, axis=-1, keepdims=True) * normal
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    return u, np.cross(normal, u)
