"""Mesh normals against central differences of the mesh's own positions, at their best step.

A central difference in t errs by truncation, growing with the step (a short segment between
nearly identical controls turns within a tenth of its parameter), and by rounding, growing as
the step shrinks (between controls 1e-9 apart a step of 1e-3 moves the rings 1e-13 of the
size: a few hundred float64 spacings). No one step suits every surface, so steps from 1e-5
up to a tenth of the segment are tried and the best agreement counts. This cannot hide a wrong
normal: the differences converge to the true normal, so a wrong one disagrees at every step.
"""

from __future__ import annotations

import numpy as np

from cgamesh.meshing.circles import mesh_circle_surface

STEPS = 9  # from 1e-4 of the widest step to the widest, evenly in log


def assert_normals_match_differences(surface, around: int, degrees: float = 0.1) -> None:
    """Normals at three rings (off the segment joints, where a linear or clamped spline may
    crease and either side's normal is right) within ``degrees`` of the normal line that
    central differences in t and theta give, away from singular points of the surface."""
    fine_around = around * 64
    columns = np.arange(0, fine_around, 64)
    for centre_t in surface.segment_count * np.array([0.13, 0.51, 0.87]):
        widest = min(0.1, 0.9 * (centre_t - np.floor(centre_t)), 0.9 * (np.ceil(centre_t) - centre_t))
        worst = []
        for step in widest * np.logspace(-4, 0, STEPS):
            fine = mesh_circle_surface(surface, fine_around, t=np.array([centre_t - step, centre_t, centre_t + step]),
                                       closed=False)
            grid = fine.positions.reshape(3, fine_around + 1, 3)
            along_t = grid[2, columns] - grid[0, columns]
            around_theta = grid[1, (columns + 1) % fine_around] - grid[1, (columns - 1) % fine_around]
            reference = np.cross(around_theta, along_t)
            strength = np.linalg.norm(reference, axis=1) / (np.linalg.norm(around_theta, axis=1)
                                                            * np.linalg.norm(along_t, axis=1))
            reference /= np.linalg.norm(reference, axis=1, keepdims=True)
            normals = fine.normals.reshape(3, fine_around + 1, 3)[1, columns]
            cosine = np.abs(np.einsum("ji,ji->j", reference, normals))
            regular = strength > 1e-3  # away from singular points of the surface
            angles = np.degrees(np.arccos(np.clip(cosine[regular], -1.0, 1.0)))
            worst.append(angles.max() if angles.size else 0.0)
        assert min(worst) <= degrees, f"normal {min(worst):.3f} degrees off at t = {centre_t:.4g}, at the best step"
