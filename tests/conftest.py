"""Shared pytest fixtures."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import settings

import gltf_validator


@pytest.fixture(scope="session")
def gltf_validate():
    """``validate(path) -> report``: the Khronos glTF-Validator.

    A missing validator is a loud skip on a developer's machine and a failure under CI
    (the CI environment variable set): in CI a missing tool is an install bug, never a pass.
    """
    reason = gltf_validator.unavailable_reason()
    if reason is not None:
        if os.environ.get("CI"):
            pytest.fail(f"CI: {reason}", pytrace=False)
        pytest.skip(f"SKIPPED, NOT VALIDATED: {reason}")
    return gltf_validator.validate_gltf


# --- shared by the geometry tests ----------------------------------------------------------------

# Under CI hypothesis draws the same examples every run (a red build is reproducible); locally
# it explores. No deadline: the first call into clifford compiles with numba.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def g3c():
    """The ``clifford.g3c`` module: the oracle, imported once per session (it costs seconds)."""
    import clifford.g3c

    return clifford.g3c


@pytest.fixture(scope="session")
def g3c_tools(g3c):
    """``clifford.tools.g3c`` (rotor generators, circle read-outs)."""
    import clifford.tools.g3c

    return clifford.tools.g3c


class CliffordOracle:
    """The paper's constructions computed object by object with clifford, independently of cgamesh.

    Only clifford's MultiVector arithmetic and its g3c tools are used here: the projection is
    eqs. 10-12 written out literally; read-outs are ``clifford.tools.g3c.get_circle_in_euc``.
    Keep the number of objects small (a few thousand at most: ~0.1 ms each).
    """

    def __init__(self, g3c, tools):
        self.g3c = g3c
        self.tools = tools
        self.layout = g3c.layout
        self.einf = g3c.einf

    def mv(self, values):
        """A clifford MultiVector from 32 coefficients in layout order."""
        return self.layout.MultiVector(np.array(values, dtype=np.float64))

    def point(self, x):
        """clifford's up() of a Euclidean point (3,)."""
        g = self.g3c
        return g.up(float(x[0]) * g.e1 + float(x[1]) * g.e2 + float(x[2]) * g.e3)

    def euclidean(self, X):
        """(3,) coefficients of e1, e2, e3 of a multivector."""
        return np.array([X[(1,)], X[(2,)], X[(3,)]], dtype=np.float64)

    def down(self, X):
        return self.euclidean(self.g3c.down(X))

    def sqrt_scalar_plus_four(self, sigma):
        """Principal square root of a scalar + 4-vector (paper eq. 10)."""
        s = sigma(0)[()]
        four = sigma(4)
        bracket = math.sqrt(s * s - (four * four)[()])  # [[Sigma]]
        return (sigma + bracket) / (math.sqrt(2.0) * math.sqrt(s + bracket))

    def project(self, interpolant):
        """C = S C' of eqs. 11-12: kS^- = sqrt(-C' ~C'), kS its 4-vector negated, S = kS / (kS kS^-)."""
        k_s_minus = self.sqrt_scalar_plus_four(-interpolant * ~interpolant)
        k_s = k_s_minus(0) - k_s_minus(4)
        denominator = k_s * k_s_minus  # a scalar
        return k_s * interpolant / denominator[()]

    def circle_euclidean(self, circle):
        """(centre (3,), unit normal (3,) up to sign, radius) of a circle, via clifford's tools."""
        centre, normal, radius = self.tools.get_circle_in_euc(circle)
        n = self.euclidean(normal)
        return self.euclidean(centre), n / np.linalg.norm(n), float(radius)

    def surface_circles(self, controls, weights, frame):
        """World (centres (A, 3), normals (A, 3), radii (A,)) of S (sum_i w_i C_i) for weights (A, n).

        controls: (n, 32) in the surface's LocalFrame ``frame``; the results are mapped to the
        world as world = origin + scale * local.
        """
        basis = [self.mv(c) for c in controls]
        centres, normals, radii = [], [], []
        for row in np.asarray(weights):
            interpolant = sum((float(w) * c for w, c in zip(row, basis) if w != 0.0), self.mv(np.zeros(32)))
            c, n, r = self.circle_euclidean(self.project(interpolant))
            centres.append(frame.origin + frame.scale * c)
            normals.append(n)
            radii.append(frame.scale * r)
        return np.array(centres), np.array(normals), np.array(radii)


@pytest.fixture(scope="session")
def oracle(g3c, g3c_tools) -> CliffordOracle:
    return CliffordOracle(g3c, g3c_tools)


def _paper_weights(kind, n, t, tension=0.0, bias=0.0, continuity=0.0, closed=False, weights=None):
    """Dense curve weights (A, n) of the controls at global parameters t (A,), from the paper's formulas.

    Written independently of cgamesh.geometry.curves (paper section 8; scene format for the ends):
    linear and kb/catmull_rom are piecewise over t in [0, segments]; bezier and
    rational_bezier are one curve over t in [0, 1].
    """
    out = np.zeros((len(t), n))
    for row, tt in enumerate(np.asarray(t, dtype=np.float64)):
        if kind in ("bezier", "rational_bezier"):
            b = np.array([math.comb(n - 1, i) * tt**i * (1 - tt) ** (n - 1 - i) for i in range(n)])
            if kind == "rational_bezier":
                w = np.asarray(weights, dtype=np.float64)
                b = b * w / np.dot(b, w)
            out[row] = b
            continue
        segments = n if closed else n - 1
        i = min(int(math.floor(tt)), segments - 1)
        a = tt - i
        if kind == "linear":
            out[row, i] += 1 - a
            out[row, i + 1] += a
            continue
        if kind == "catmull_rom":
            tension = bias = continuity = 0.0

        def idx(k):
            return k % n if closed else min(max(k, 0), n - 1)

        def unit(k):
            e = np.zeros(n)
            e[idx(k)] = 1.0
            return e

        t_, b_, c_ = tension, bias, continuity
        v_start = ((1 - t_) * (1 + b_) * (1 + c_) / 2 * (unit(i) - unit(i - 1))
                   + (1 - t_) * (1 - b_) * (1 - c_) / 2 * (unit(i + 1) - unit(i)))
        v_end = ((1 - t_) * (1 + b_) * (1 - c_) / 2 * (unit(i + 1) - unit(i))
                 + (1 - t_) * (1 - b_) * (1 + c_) / 2 * (unit(i + 2) - unit(i + 1)))
        out[row] = ((2 * a**3 - 3 * a**2 + 1) * unit(i) + (a**3 - 2 * a**2 + a) * v_start
                    + (-2 * a**3 + 3 * a**2) * unit(i + 1) + (a**3 - a**2) * v_end)
    return out


@pytest.fixture(scope="session")
def paper_weights():
    """``weights(kind, n, t, tension=, bias=, continuity=, closed=, weights=) -> (A, n)``."""
    return _paper_weights


@pytest.fixture(scope="session")
def chromium():
    """Path of a headless-capable Chromium (Debian's ``chromium``, installed by .ci/run).

    Missing: a loud skip on a developer's machine and a failure under CI, like the validator.
    """
    import shutil

    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    reason = "chromium is not installed (apt-get install chromium): the viewer page cannot be tested"
    if os.environ.get("CI"):
        pytest.fail(f"CI: {reason}", pytrace=False)
    pytest.skip(f"SKIPPED, NOT TESTED: {reason}")
