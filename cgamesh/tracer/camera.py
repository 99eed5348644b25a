"""The pinhole camera of paper section 3 and its rays, for all pixels at once (eq. 2).

At the origin the camera looks along e2 with e1 to its right and e3 up. The model-view rotor
R_MV = T R takes it to its pose: R turns (e1, e2, e3) into (right, forward, up) and T moves
the origin to the camera's position. Pixel (i, j) (j = 0 the bottom row) has its centre at

    W_ij = F(f e2 - x_max/2 (1 - 2 (i + 1/2) / w) e1 - y_max/2 (1 - 2 (j + 1/2) / h) e3),
    P_ij = R_MV W_ij ~R_MV,      L_ij = X0 ^ P_ij ^ n_inf,      X0 = R_MV n_0 ~R_MV,

(the paper's formula puts i, j at a pixel's corner; here they are its centre). The sandwich
is applied as the 5 x 5 matrix it is on vectors (``rotors.versor_matrix``). Images are
returned top row first, as PNG stores them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.algebra.conformal import N_0, up
from cgamesh.geometry.algebra.layout import BLADE_COUNT, blade_index, grade_indices
from cgamesh.geometry.algebra.rotors import translator, versor_matrix
from cgamesh.tracer.rays import Rays

_VECTORS = grade_indices(1)
_E12, _E13, _E23 = blade_index("e12"), blade_index("e13"), blade_index("e23")
# The default view direction (from the scene towards the camera) in a z-up file.
_VIEW_FROM_Z_UP = np.array([1.0, -1.6, 0.9])


def rotor_from_matrix(matrix: np.ndarray) -> np.ndarray:
    """The rotation rotor (32,) of a proper orthogonal matrix (3, 3) (columns = images of e1, e2, e3).

    From the quaternion (w, x, y, z) of the matrix, R = w - x e23 - y e31 - z e12.
    """
    m = np.asarray(matrix, dtype=np.float64)
    trace = np.trace(m)
    if trace > 0.0:
        s = 2.0 * np.sqrt(1.0 + trace)
        w, x, y, z = 0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s
    else:
        k = int(np.argmax(np.diag(m)))
        i, j = (k + 1) % 3, (k + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[k, k] - m[i, i] - m[j, j])
        q = np.empty(3)
        q[k] = 0.25 * s
        q[i] = (m[i, k] + m[k, i]) / s
        q[j] = (m[j, k] + m[k, j]) / s
        w = (m[j, i] - m[i, j]) / s
        x, y, z = q
    rotor = np.zeros(BLADE_COUNT)
    rotor[0], rotor[_E23], rotor[_E13], rotor[_E12] = w, -x, y, -z
    return rotor / np.sqrt(w * w + x * x + y * y + z * z)


@dataclass(frozen=True)
class Camera:
    """position, look_at, up (3,); focal length f; image plane bounds x_max and y_max (None:
    x_max times the image's height / width)."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float]
    focal_length: float = 1.0
    x_max: float = 1.0
    y_max: float | None = None

    @cached_property
    def axes(self) -> np.ndarray:
        """(3, 3) columns right, forward, up of the camera in the world."""
        forward = np.subtract(self.look_at, self.position).astype(np.float64)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(self.up, dtype=np.float64))
        right /= np.linalg.norm(right)
        return np.stack([right, forward, np.cross(right, forward)], axis=1)

    @cached_property
    def model_view(self) -> np.ndarray:
        """R_MV = T R (32,)."""
        rotation = rotor_from_matrix(self.axes)
        return products.geometric(translator(np.asarray(self.position, dtype=np.float64)), rotation,
                                  (0, 2), (0, 2), (0, 2, 4))

    def bounds(self, width: int, height: int) -> tuple[float, float]:
        return self.x_max, (self.y_max if self.y_max is not None else self.x_max * height / width)

    def rays(self, width: int, height: int, rows: slice = slice(None)) -> Rays:
        """The rays of the pixels of image rows ``rows`` (row 0 at the top), row by row."""
        x_max, y_max = self.bounds(width, height)
        row = np.arange(height)[rows]
        i = np.arange(width)
        j = height - 1 - row
        x = -0.5 * x_max * (1.0 - 2.0 * (i + 0.5) / width)
        z = -0.5 * y_max * (1.0 - 2.0 * (j + 0.5) / height)
        local = np.empty((len(row), width, 3))
        local[..., 0] = x[None, :]
        local[..., 1] = self.focal_length
        local[..., 2] = z[:, None]
        w = up(local.reshape(-1, 3))
        sandwich = versor_matrix(self.model_view)
        p = np.zeros_like(w)
        p[:, _VECTORS] = w[:, _VECTORS] @ sandwich.T
        x0 = np.zeros(BLADE_COUNT)
        x0[_VECTORS] = sandwich @ N_0[_VECTORS]
        return Rays.through_points(x0, p)

    def project(self, points: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Continuous pixel coordinates (K, 2) (column, row from the top; pixel centres at
        k + 1/2) and depths along the view axis (K,) of world points (K, 3)."""
        x_max, y_max = self.bounds(width, height)
        q = (np.asarray(points, dtype=np.float64) - np.asarray(self.position)) @ self.axes
        depth = q[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = self.focal_length * q[:, 0] / depth
            z = self.focal_length * q[:, 2] / depth
        column = 0.5 * width * (1.0 + 2.0 * x / x_max)
        row = height - 0.5 * height * (1.0 + 2.0 * z / y_max)
        return np.stack([column, row], axis=1), depth

    @classmethod
    def framing(cls, centre: np.ndarray, radius: float, up_axis: str) -> "Camera":
        """A camera looking at a sphere (centre, radius) from above and to the side, fitting it."""
        view = _VIEW_FROM_Z_UP if up_axis == "z" else _VIEW_FROM_Z_UP[[0, 2, 1]] * np.array([1.0, 1.0, -1.0])
        view = view / np.linalg.norm(view)
        focal, x_max = 1.0, 1.0
        half_angle = np.arctan(0.5 * 0.75 * x_max / focal)  # the narrower (vertical) half angle at 4:3
        distance = 1.1 * radius / np.sin(half_angle)
        up_vector = (0.0, 0.0, 1.0) if up_axis == "z" else (0.0, 1.0, 0.0)
        position = np.asarray(centre, dtype=np.float64) + distance * view
        return cls(tuple(position), tuple(np.asarray(centre, dtype=np.float64)), up_vector, focal, x_max)
