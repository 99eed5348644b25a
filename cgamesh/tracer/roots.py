"""The intersection functions of rays with the objects of an evolved surface, and their roots.

A ray L meets the circle C(t) = S C'(t) where (L v C)^2 = 0, and the point pair P(t) where
L v P = 0 (it meets the carrier line; ``evolved`` checks that the point lies between the end
points). ``SurfaceRoots`` finds these roots per curve segment for a batch of rays given as
lines in the surface's local frame, by either finder:

Closed form (sections 5.1.2, 7.1). With Sigma = -C' ~C' = s + F (scalar + 4-vector),
beta = [[Sigma]] and q = F^2 = s^2 - beta^2, the projected object is C ~ (s + beta - F) C'
(and (s +- beta - F) C' is again of C's grade). So with

    W+ = <L (s + beta - F) C'>,   W- = <L (s - beta - F) C'>,   s - beta = q / (s + beta),

W+ is L v C up to a positive factor (a 4-vector before the dual for circles, the I5
coefficient for point pairs), and the product of the two branches is a polynomial in alpha:
for circles P = (W+)^2 (W-)^2 = (A^2 + beta^2 B^2)^2 - 4 beta^2 (A . B)^2 with
A = <L (s - F) C'>, B = <L C'> (eq. 16), of degree 12 d; for point pairs P = W+ W- =
a^2 - beta^2 b^2 (eq. 31), of degree 6 d; d is the degree of C' in alpha (1 linear, N a
Bezier curve of order N, also rational once its positive denominator is multiplied out,
3 Kochanek-Bartels). A rational curve's denominator, multiplied out, scales P by its 12th
power (circles): with weights from 1e-3 to 1e3 that spans more than float64 holds, so its
segments are fitted in pieces over which the denominator changes by at most PIECE_RATIO
(``pieces``). P is evaluated as the product of its factors, which has no
cancellation (the expanded form loses all precision where F is small, since W- is then).
W+ and W- are linear in L, so for a batch of rays they are one matrix product with matrices
precomputed per segment at Chebyshev points, where P is fitted exactly; its roots are
colleague-matrix eigenvalues (``chebyshev``).

Known roots. Every curve passes through its controls, which are blades, at the ends of a
segment: there F = 0, so W- vanishes for every ray (and wherever else the interpolant passes
through a blade, e.g. the middle of a symmetric curve). P has double roots (circles) or
simple roots (pairs) there; they are found once per segment and divided out, leaving degree
12 d - 4 or 6 d - 2 when only the ends are known (8 for linear circles, 4 for linear pairs,
32 for a Kochanek-Bartels segment of circles). Left in, they meet a true root nearby (a ray
through a segment's end circle) as a triple root, which no eigenvalue solver resolves
better than the cube root of the rounding. When F vanishes for every alpha (circles on one
sphere, co-circular point pairs: section 7.3) W- is identically zero and W+ = 2 s B is the
polynomial itself: of degree 2 d (circles, squared) or d (point pairs).

Acceptance. The eigenvalues' real parts (complex ones near the real axis too: a cluster
split by rounding) are polished by Newton steps on P, and the known roots join them as
candidates. A candidate is kept where |(L v C)^2| (or |L v P|) is below ROOT_RTOL of the size
of its terms, (|L| |C|)^2 (or |L| |P|) in coefficient norms; one below REFINE_BELOW first gets
Newton steps on the true function, with dC/dalpha from the projection's closed-form
derivative. That rejects the roots of W- (extraneous, from the squaring: there W+ = 2 beta B,
as large as its terms) and complex pairs, and recovers the true roots inside clusters.

Sampled (section 5.1.1): the same functions at N + 1 objects per segment, sign changes and
a local quadratic, plus grazing double roots (``sampled``). No polishing: that is the
paper's algorithm, whose accuracy against N the benchmark measures.

Motor surfaces (docs/interpolation.md) have no interpolant C' whose blend is polynomial in
alpha, so no exact intersection polynomial. "polynomial" then samples (L v C)^2 on the
MOTOR_PROXY_DEGREE + 1 circles at a segment's Chebyshev points and takes the real roots of
the interpolating Chebyshev series (a proxy of the smooth function: colleague-matrix
eigenvalues, as for blade surfaces); "sampled" is the sampled finder at N + 1 circles:
its sign changes, plus a pair of starting points at every dip of |f| that does not change
sign (``sampled.dip_pairs``: a ray in or near a circle's plane meets the tube twice within a
fraction of a step, the samples only touch the pair). The proxy's candidates get
MOTOR_NEWTON_STEPS Newton steps on the true function (dC/dt in closed form); the sampled
finder's get up to MOTOR_PAIR_STEPS (Newton's steps only halve the error of a pair until they
resolve it), and the second of a pair (a dip's, or two sign changes either side of one sample
that converged on one root) is polished on f / (t - t1), t1 the first's root (deflation), so
that the two converge on the two roots, not twice on the nearer one. Every candidate is then
accepted like a polynomial root, by its residual.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from cgamesh.geometry.algebra import products
from cgamesh.geometry.curves.bezier import Bezier, RationalBezier, bernstein
from cgamesh.geometry.curves.kochanek_bartels import KochanekBartels
from cgamesh.geometry.curves.linear import Linear
from cgamesh.errors import InvalidInputError
from cgamesh.geometry.surface import EvolvedSurface
from cgamesh.tracer import cga, chebyshev, sampled

FINDERS = ("polynomial", "sampled")
DEFAULT_SAMPLES = 64
# The sampled finder evaluates at most about this many values at once (bounds its memory).
SAMPLED_CHUNK = 4_000_000
# Acceptance of a polished root, relative to the size of the function's terms.
ROOT_RTOL = {3: 1e-10, 2: 1e-10}
# Candidates with a larger residual than that but below this get Newton steps on the true function.
REFINE_BELOW = 1e-2
REFINE_STEPS = 3
# Newton steps polishing every sampled root of a motor surface.
MOTOR_NEWTON_STEPS = 6
# ... and the roots of a pair at a dip of the sampled finder: Newton's steps only halve the
# error until they resolve the pair (a double root), so more of them, stopping when converged.
MOTOR_PAIR_STEPS = 40
# A candidate's Newton iteration stops once its step (in t) is below this.
NEWTON_CONVERGED = 1e-15
# Two polished roots of one ray closer than this (in t) are one root found twice.
PAIR_MERGED = 1e-12
# Degree of the Chebyshev proxy of (L v C)^2 on a motor segment.
MOTOR_PROXY_DEGREE = 32
# |F| below this fraction of its largest on a segment may be a zero of W- for every ray ...
STRUCTURAL_RTOL = 1e-9
# ... and is one when, after Gauss-Newton steps towards the least |F|, |F| is below this fraction
# of the scalar part s of Sigma there (the size of Sigma's terms, at any scale of C'): a true
# zero computes to rounding, about 1e-16 s.
STRUCTURAL_LOCAL_RTOL = 1e-13
STRUCTURAL_STEPS = 4
STRUCTURAL_STEP = 1e-7
# A rational curve's interpolant, its denominator multiplied out, is fitted on pieces of a
# segment over which the denominator changes by at most this factor: P grows as its 12th power
# (circles), so one fit over weights from 1e-3 to 1e3 would lose the light end to rounding.
PIECE_RATIO = 2.0
MAX_PIECES = 256


@dataclass(frozen=True)
class RootFinder:
    """kind: "polynomial" or "sampled"; samples: objects per segment for "sampled"."""

    kind: str = "polynomial"
    samples: int = DEFAULT_SAMPLES

    def __post_init__(self):
        if self.kind not in FINDERS:
            raise InvalidInputError(f"root finder must be one of {', '.join(FINDERS)}, got {self.kind!r}")
        if self.samples < 2:
            raise InvalidInputError(f"the sampled root finder needs at least 2 samples per segment, got {self.samples}")


def interpolant_degree(curve) -> int:
    """Degree in alpha of the (numerator of the) interpolant C'(alpha) on one segment."""
    if isinstance(curve, Linear):
        return 1
    if isinstance(curve, (Bezier, RationalBezier)):
        return curve.control_count - 1
    if isinstance(curve, KochanekBartels):
        return 3
    raise InvalidInputError(f"the tracer does not know the degree of curve {type(curve).__name__}")


@lru_cache(maxsize=None)
def meet_tensor(grade: int) -> np.ndarray:
    """T (10, k, o): the part of L X whose dual is L v X (eq. 3) as a bilinear map, for lines L
    (grade 3) and objects X of ``grade``: <L X>_4 for circles (o = 5), <L X>_5 for pairs (o = 1)."""
    out_grade = 4 if grade == 3 else 5
    line_basis = np.eye(32)[cga.GRADE_BLADES[3]]
    object_basis = np.eye(32)[cga.GRADE_BLADES[grade]]
    table = cga.product(line_basis[:, None, :], object_basis[None, :, :], (3,), (grade,), (out_grade,))
    return table[..., cga.GRADE_BLADES[out_grade]]


def meet_matrix(objects: np.ndarray, grade: int) -> np.ndarray:
    """(10, M * o) matrix taking line coefficients to <L X_m> for objects X_m (M, 32)."""
    tensor = meet_tensor(grade)
    m = np.einsum("ijo,mj->imo", tensor, objects[:, cga.GRADE_BLADES[grade]])
    return m.reshape(tensor.shape[0], -1)


def meet_values(line_coefficients: np.ndarray, matrix: np.ndarray, grade: int) -> np.ndarray:
    """(n, M, o) values <L X_m> for line coefficients (n, 10)."""
    out = line_coefficients @ matrix
    return out.reshape(out.shape[0], -1, 5 if grade == 3 else 1)


_FOUR_SIGNS = cga.scalar_signs(4)


def _square(values: np.ndarray) -> np.ndarray:
    """Metric squares of 4-vectors (..., 5) (their squares are scalars)."""
    return np.einsum("...o,o->...", values * values, _FOUR_SIGNS)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...o,...o,o->...", a, b, _FOUR_SIGNS)


@dataclass(frozen=True)
class _Polynomial:
    """Per segment: the degree of P and the matrices giving W+ (and W-, unless the surface is
    free of 4-vectors) at the Chebyshev points."""

    degree: int
    map_plus: np.ndarray
    map_minus: np.ndarray | None
    divisor: np.ndarray
    fit: np.ndarray


@dataclass(frozen=True)
class _Samples:
    """Per segment: the sampled objects' parameters t (K,) and the matrix giving <L C(t_k)>."""

    t: np.ndarray
    matrix: np.ndarray


class SurfaceRoots:
    """Roots of the intersection functions of rays with one surface, segment by segment."""

    def __init__(self, surface: EvolvedSurface):
        self.surface = surface
        self.grade = surface.grade
        self.motor = surface.interpolation == "motor"
        self.degree = None if self.motor else interpolant_degree(surface.curve)
        self._polynomials: dict[int, _Polynomial] = {}
        self._known: dict[int, np.ndarray] = {}
        self._pieces: dict[int, list[tuple[float, float]]] = {}
        self._samples: dict[tuple[int, int], _Samples] = {}

    def interpolant(self, t: np.ndarray) -> np.ndarray:
        """C'(t) (M, 32), with a rational curve's positive denominator multiplied out."""
        value, _ = self.surface.curve.basis(t).evaluate(self.surface.controls)
        curve = self.surface.curve
        if isinstance(curve, RationalBezier):
            value = value * (bernstein(curve.control_count - 1, t) @ np.asarray(curve.weights))[:, None]
        return value

    def four_vector(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """C' (M, 32) and Sigma = -C' ~C' = s + F (M, 32) at parameters t."""
        g = self.grade
        interpolant = self.interpolant(t)
        sigma = -cga.product(interpolant, products.reverse(interpolant), (g,), (g,), (0, 4))
        return interpolant, sigma

    def pieces(self, segment: int) -> list[tuple[float, float]]:
        """[t0, t1] pieces covering the segment, each fitted apart: the whole segment, except for
        a rational curve whose denominator changes by more than PIECE_RATIO over it, which is
        halved until each piece's does not (sampled at 17 points per piece)."""
        if segment not in self._pieces:
            curve = self.surface.curve
            out, todo = [], [(float(segment), float(segment + 1))]
            while todo:
                a, b = todo.pop()
                if isinstance(curve, RationalBezier) and len(out) + len(todo) < MAX_PIECES:
                    d = bernstein(curve.control_count - 1, np.linspace(a, b, 17) - segment) @ np.asarray(curve.weights)
                    if d.max() > PIECE_RATIO * d.min():
                        middle = 0.5 * (a + b)
                        todo.extend([(middle, b), (a, middle)])
                        continue
                out.append((a, b))
            self._pieces[segment] = out
        return self._pieces[segment]

    def structural_zeros(self, segment: int, piece: tuple[float, float] | None = None) -> np.ndarray:
        """u in [-1, 1] over the piece (default: the whole segment) where F (so W- for every
        ray) vanishes: the segment's ends (its controls are blades) and any interior place
        where the interpolant passes through a blade.

        |F|^2 (coefficient norm) is a polynomial of degree 4 d, fitted exactly; its zeros are
        double roots, found among the roots of its derivative. A candidate is kept only where
        F truly vanishes: below STRUCTURAL_RTOL of its largest value on the segment, and,
        after Gauss-Newton steps to the least |F| nearby, below STRUCTURAL_LOCAL_RTOL of Sigma's
        scalar part there. The local test matters where the curve's scale varies: a rational
        curve with weights 1e3 and 1e-3 is a blade to 1e-11 of its size for a stretch near an
        end, and dividing P by a zero it does not have puts its roots out by the surface's width.
        """
        a, b = piece if piece is not None else (float(segment), float(segment + 1))
        at = lambda u: a + 0.5 * (b - a) * (u + 1.0)  # noqa: E731
        degree = 4 * self.degree
        u = chebyshev.nodes(degree)
        _, sigma = self.four_vector(at(u))
        size = np.einsum("mi,mi->m", sigma[:, cga.GRADE_BLADES[4]], sigma[:, cga.GRADE_BLADES[4]])
        series = chebyshev.coefficients(size[None, :])[0]
        critical = chebyshev.roots(np.polynomial.chebyshev.chebder(series)[None, :])[0]
        critical = critical[~np.isnan(critical)]
        zeros = [u for u, end in ((-1.0, a), (1.0, b)) if end in (segment, segment + 1)]
        if critical.size:
            _, at_critical = self.four_vector(at(critical))
            norm = np.linalg.norm(at_critical[:, cga.GRADE_BLADES[4]], axis=1)
            small = critical[norm <= STRUCTURAL_RTOL * np.sqrt(size.max())]
            refined, relative = self._least_four_vector(at, small)
            for z in refined[relative <= STRUCTURAL_LOCAL_RTOL]:
                if all(abs(z - known) > 1e-6 for known in zeros):
                    zeros.append(float(z))
        return np.array(zeros)

    def _least_four_vector(self, at, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Newton steps from u (k,) towards the least |F| nearby (F' by central differences);
        returns the refined u and |F| / |s| there."""
        four = cga.GRADE_BLADES[4]
        for _ in range(STRUCTURAL_STEPS):
            if u.size == 0:
                break
            t = at(np.concatenate([u, u - STRUCTURAL_STEP, u + STRUCTURAL_STEP]))
            _, sigma = self.four_vector(t)
            f, low, high = np.split(sigma[:, four], 3)
            rate = (high - low) / (2.0 * STRUCTURAL_STEP)
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.einsum("ki,ki->k", f, rate) / np.einsum("ki,ki->k", rate, rate)
            u = np.clip(u - np.nan_to_num(step, posinf=0.0, neginf=0.0), -1.0, 1.0)
        _, sigma = self.four_vector(at(u))
        with np.errstate(divide="ignore", invalid="ignore"):
            relative = np.linalg.norm(sigma[:, four], axis=1) / np.abs(sigma[:, 0])
        return u, np.nan_to_num(relative, nan=np.inf)

    def polynomial(self, segment: int, piece: tuple[float, float] | None = None) -> _Polynomial:
        """The intersection polynomial over a piece of a segment (default: its first), as
        matrices giving its factors at fitting points."""
        piece = self.pieces(segment)[0] if piece is None else piece
        if piece not in self._polynomials:
            g = self.grade
            free = self.surface.four_vector_free
            degree = (1 if free else 6) * (2 if g == 3 else 1) * self.degree
            multiplicity = 2 if g == 3 else 1
            zeros = np.zeros(0) if free else self.structural_zeros(segment, piece)
            degree -= multiplicity * zeros.size  # the roots of W- known for every ray
            # Points where P is fitted, away from the known roots it is divided by.
            for shift in (0.0, 0.25, -0.25, 0.125):
                u, fit = chebyshev.shifted_nodes(degree, shift)
                if zeros.size == 0 or np.abs(u[:, None] - zeros[None, :]).min() > 1e-3:
                    break
            interpolant, sigma = self.four_vector(piece[0] + 0.5 * (piece[1] - piece[0]) * (u + 1.0))
            divisor = np.prod((u[:, None] - zeros[None, :]) ** multiplicity, axis=1)
            if free:
                self._polynomials[piece] = _Polynomial(degree, meet_matrix(interpolant, g), None, divisor, fit)
            else:
                s, four = sigma[:, 0], products.grade(sigma, 4)
                q = cga.metric_square(four, 4)
                beta = np.sqrt(s * s - q)
                four_part = cga.product(four, interpolant, (4,), (g,), (g,))
                plus = (s + beta)[:, None] * interpolant - four_part
                minus = (q / (s + beta))[:, None] * interpolant - four_part
                self._polynomials[piece] = _Polynomial(degree, meet_matrix(plus, g), meet_matrix(minus, g), divisor,
                                                       fit)
        return self._polynomials[piece]

    def samples_of(self, segment: int, count: int) -> _Samples:
        """The segment's count + 1 sampled objects (including both ends), as a matrix."""
        key = (segment, count)
        if key not in self._samples:
            t = segment + np.linspace(0.0, 1.0, count + 1)
            self._samples[key] = _Samples(t, meet_matrix(self.surface.sample(t).blades, self.grade))
        return self._samples[key]

    def polynomial_degree(self, segment: int) -> int:
        """Degree of the intersection polynomial solved on a segment (after the known roots of W-
        are divided out): 8 for linear circles, 4 for linear point pairs (see the module doc); a
        motor surface's is its Chebyshev proxy's, MOTOR_PROXY_DEGREE."""
        if self.motor:
            return MOTOR_PROXY_DEGREE
        return self.polynomial(segment).degree

    def _proxy_roots(self, coefficients: np.ndarray, segment: int) -> tuple[np.ndarray, np.ndarray]:
        """(ray index (R,), t (R,)) of the real roots of the Chebyshev proxy of (L v C)^2 on a
        segment (motor surfaces), with both segment ends as candidates too (a ray through an end
        circle meets the proxy's roots there only roughly)."""
        key = (segment, -MOTOR_PROXY_DEGREE)
        if key not in self._samples:
            u = chebyshev.nodes(MOTOR_PROXY_DEGREE)
            t = segment + 0.5 * (u + 1.0)
            self._samples[key] = _Samples(t, meet_matrix(self.surface.sample(t).blades, self.grade))
        matrix = self._samples[key].matrix
        found = [(np.zeros(0, dtype=np.int64), np.zeros(0))]
        chunk = max(1, SAMPLED_CHUNK // matrix.shape[1])
        for start in range(0, len(coefficients), chunk):
            f = _square(meet_values(coefficients[start:start + chunk], matrix, self.grade))
            size = np.abs(f).max(axis=1, keepdims=True)
            series = chebyshev.coefficients(f / np.where(size > 0.0, size, 1.0))
            u = chebyshev.roots(series)
            which, column = np.nonzero(~np.isnan(u))
            u = chebyshev.polish(series[which], u[which, column])
            ends = np.arange(f.shape[0])
            found.append((start + np.concatenate([which, ends, ends]),
                          np.concatenate([segment + 0.5 * (u + 1.0), np.full(ends.size, float(segment)),
                                          np.full(ends.size, segment + 1.0)])))
        which, t = (np.concatenate(parts) for parts in zip(*found))
        return which, t

    def _sampled(self, lines: np.ndarray, coefficients: np.ndarray, segment: int,
                 count: int) -> tuple[np.ndarray, np.ndarray]:
        """(ray index (R,), t (R,)) of the sampled finder's roots on a segment (motor surfaces),
        in chunks, polished: sign changes by Newton steps (deflated where two converged on one
        root), the pairs at dips by Newton steps on the first and deflated steps on the second
        (see the module doc)."""
        samples = self.samples_of(segment, count)
        chunk = max(1, SAMPLED_CHUNK // samples.matrix.shape[1])
        found = [(np.zeros(0, dtype=np.int64), np.zeros(0))]
        for start in range(0, len(coefficients), chunk):
            values = meet_values(coefficients[start:start + chunk], samples.matrix, self.grade)
            f = _square(values) if self.grade == 3 else values[..., 0]
            which, start_t = sampled.sign_change_roots(f, samples.t, grazing=False)
            which = start + which
            t = self.newton(lines[which], start_t, segment, MOTOR_PAIR_STEPS)
            # two sign changes on either side of one sample (a pair straddling it) may converge
            # on the same root: the second of each such pair is polished again, deflated
            order = np.lexsort((t, which))
            same = (np.diff(which[order]) == 0) & (np.diff(t[order]) <= PAIR_MERGED)
            again, kept = order[1:][same], order[:-1][same]
            t[again] = self.newton(lines[which[again]], start_t[again], segment, MOTOR_PAIR_STEPS,
                                   deflate=t[kept])
            found.append((which, t))
            row, first, second = sampled.dip_pairs(f, samples.t)
            row = start + row
            root = self.newton(lines[row], first, segment, MOTOR_PAIR_STEPS)
            # the other root of the pair: the parabola's roots sum to twice its extremum, so the
            # mirror of the first root about it is where the second is expected
            other = self.newton(lines[row], np.clip(first + second - root, segment, segment + 1.0), segment,
                                MOTOR_PAIR_STEPS, deflate=root)
            found.append((np.concatenate([row, row]), np.concatenate([root, other])))
        which, t = (np.concatenate(parts) for parts in zip(*found))
        return which, t

    def known_roots(self, segment: int) -> np.ndarray:
        """Parameters t in [segment, segment + 1] where W- vanishes for every ray (divided out)."""
        if self.motor or self.surface.four_vector_free:
            return np.zeros(0)
        if segment not in self._known:
            known = [a + 0.5 * (b - a) * (self.structural_zeros(segment, (a, b)) + 1.0)
                     for a, b in self.pieces(segment)]
            self._known[segment] = np.unique(np.concatenate(known))
        return self._known[segment]

    def objects(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """X+ = (s + beta - F) C' (a positive multiple of C(t), no projection needed) and
        X- = (s - beta - F) C' (None when the surface is free of 4-vectors) at parameters t (R,)."""
        if self.motor:  # circles by construction: no projection, no second branch
            return self.surface.sample(t).blades, None
        g = self.grade
        interpolant = self.interpolant(t)
        if self.surface.four_vector_free:
            return interpolant, None
        sigma = -cga.product(interpolant, products.reverse(interpolant), (g,), (g,), (0, 4))
        s, four = sigma[:, 0], products.grade(sigma, 4)
        q = cga.metric_square(four, 4)
        beta = np.sqrt(np.maximum(s * s - q, 0.0))
        four_part = cga.product(four, interpolant, (4,), (g,), (g,))
        with np.errstate(divide="ignore", invalid="ignore"):
            minus = (q / (s + beta))[:, None] * interpolant - four_part
        return (s + beta)[:, None] * interpolant - four_part, minus

    def line_values(self, lines: np.ndarray, objects: np.ndarray) -> np.ndarray:
        """<L X> per row: 4-vector coefficients (R, 5) for circles, the I5 coefficient (R, 1) for pairs."""
        g = self.grade
        out = cga.product(lines, objects, (3,), (g,), (4 if g == 3 else 5,))
        return out[:, cga.GRADE_BLADES[4 if g == 3 else 5]]

    def residual(self, lines: np.ndarray, objects: np.ndarray) -> np.ndarray:
        """|(L v C)^2| / (|L| |C|)^2 (circles) or |L v P| / (|L| |P|) (pairs), per row, for
        objects of any positive scale: the function's value relative to the size of its terms."""
        value = self.line_values(lines, objects)
        size = np.linalg.norm(lines, axis=1) * np.linalg.norm(objects, axis=1)
        if self.grade == 3:
            return np.abs(_square(value)) / (size * size)
        return np.abs(value[:, 0]) / size

    def newton(self, lines: np.ndarray, t: np.ndarray, segment: int, steps: int = REFINE_STEPS,
               deflate: np.ndarray | None = None) -> np.ndarray:
        """Newton steps on the true function (L v C)^2 (or L v P) with dC/dt from the projection's
        closed-form derivative, inside the segment. With ``deflate`` (roots r (R,) already
        found), on g = f / (t - r) instead: its step g / g' = f d / (f' d - f), d = t - r, does
        not fall back into r (where g keeps a root only if f has a double root there). A
        candidate whose step falls to NEWTON_CONVERGED stops there."""
        t = t.copy()
        active = np.arange(t.size)
        for _ in range(steps):
            if active.size == 0:
                break
            at = t[active]
            projection = self.surface.sample(at)
            value = self.line_values(lines[active], projection.blades)
            rate = self.line_values(lines[active], projection.derivatives)
            if self.grade == 3:
                f, df = _square(value), 2.0 * _dot(value, rate)
            else:
                f, df = value[:, 0], rate[:, 0]
            if deflate is not None:
                d = at - deflate[active]
                f, df = f * d, df * d - f
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.where(df != 0.0, f / df, 0.0)
            step = np.clip(np.nan_to_num(step), -0.1, 0.1)
            t[active] = np.clip(at - step, segment, segment + 1.0)
            active = active[np.abs(step) > NEWTON_CONVERGED]
        return t

    def true_roots(self, lines: np.ndarray, t: np.ndarray, segment: int, rtol: float):
        """(t, accepted mask, C up to a positive factor) for candidate roots t of rays ``lines``.

        Kept where the relative residual (``residual``) is below rtol: a root of W-
        (extraneous) leaves W+ = 2 beta B there, as large as its terms. A root the eigenvalues
        gave only roughly (a cluster: a ray through a segment's end circle meets W-'s double
        root there, a grazing ray a double root of W+) is first refined by Newton steps on
        the true function when its residual is below REFINE_BELOW.
        """
        plus, _ = self.objects(t)
        residual = self.residual(lines, plus)
        rough = (residual > ROOT_RTOL[self.grade]) & (residual <= REFINE_BELOW)
        if np.any(rough):
            t = t.copy()
            t[rough] = self.newton(lines[rough], t[rough], segment)
            plus[rough] = self.objects(t[rough])[0]
            residual[rough] = self.residual(lines[rough], plus[rough])
        return t, residual <= rtol, plus

    def roots(self, lines: np.ndarray, segment: int, finder: RootFinder, rtol: float):
        """Roots on one segment of local rays ``lines`` (n, 32): (ray index (R,), t (R,), the
        objects there up to a positive factor (R, 32))."""
        rows = np.arange(len(lines))
        coefficients = lines[:, cga.GRADE_BLADES[3]]
        g = self.grade
        if self.motor:
            if finder.kind == "sampled":
                which, t = self._sampled(lines, coefficients, segment, finder.samples)
            else:
                which, t = self._proxy_roots(coefficients, segment)
                t = self.newton(lines[which], t, segment, MOTOR_NEWTON_STEPS)
            objects = self.objects(t)[0]
            ok = self.residual(lines[which], objects) <= rtol
            return rows[which][ok], t[ok], objects[ok]
        if finder.kind == "sampled":
            samples = self.samples_of(segment, finder.samples)
            chunk = max(1, SAMPLED_CHUNK // samples.matrix.shape[1])
            found = [(np.zeros(0, dtype=np.int64), np.zeros(0))]
            for start in range(0, rows.size, chunk):
                values = meet_values(coefficients[start:start + chunk], samples.matrix, g)
                f = _square(values) if g == 3 else values[..., 0]
                which, t = sampled.sign_change_roots(f, samples.t)
                found.append((start + which, t))
            which, t = (np.concatenate(parts) for parts in zip(*found))
            return rows[which], t, self.objects(t)[0]
        found = [self._piece_roots(lines, coefficients, segment, piece, rtol) for piece in self.pieces(segment)]
        return tuple(np.concatenate(parts) for parts in zip(*found))

    def _piece_roots(self, lines: np.ndarray, coefficients: np.ndarray, segment: int, piece: tuple[float, float],
                     rtol: float):
        rows = np.arange(len(lines))
        g = self.grade
        poly = self.polynomial(segment, piece)
        plus = meet_values(coefficients, poly.map_plus, g)
        values = _square(plus) if g == 3 else plus[..., 0]
        if poly.map_minus is not None:
            minus = meet_values(coefficients, poly.map_minus, g)
            values = values * (_square(minus) if g == 3 else minus[..., 0]) / poly.divisor
        size = np.abs(values).max(axis=1, keepdims=True)
        values = values / np.where(size > 0.0, size, 1.0)
        series = values @ poly.fit.T
        u = chebyshev.roots(series)
        which, column = np.nonzero(~np.isnan(u))
        u = chebyshev.polish(series[which], u[which, column])
        # A true root next to a known root of W- sits in a cluster of roots of P, which the
        # eigenvalues resolve only roughly: the known roots are candidates too, to be refined.
        a, b = piece
        known = [t for t in self.known_roots(segment) if a <= t <= b]
        which = np.concatenate([which, np.repeat(np.arange(rows.size), len(known))])
        t = np.concatenate([a + 0.5 * (b - a) * (u + 1.0), np.tile(known, rows.size)])
        t, ok, objects = self.true_roots(lines[which], t, segment, rtol)
        return rows[which][ok], t[ok], objects[ok]
