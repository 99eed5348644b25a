"""Node ring normals of centreline inputs that keep each node's ring inside the radius envelope.

A skeleton or streamline gives centres and radii only; the ring at a node is the circle of
that centre and radius, and cgamesh chooses its plane: perpendicular to the path, the bisector
of the unit chords on either side (``cgamesh.pipelines.tubes.node_tangents``), which is the
tangent of the motor tube's centre curve there (a chord-length Catmull-Rom spline, docs/interpolation.md
section 2). At a sharp turn onto a short span that thins fast, that ring can leave the radius
envelope by itself: its inner side reaches over the thin span, nearer to it than to any fat
part of the centreline (on navis' neuron 722817260, a node of radius 68 at a 70-degree turn
onto a span of 70 that thins to 20 reaches 1.69 radii from the centreline, measured at the
nearest centreline point). No tube through that ring can stay inside the envelope there.

So before meshing each interior node is measured against its neighbourhood: the rings the
motion will draw on its two spans (RINGS_PER_SPAN per span, from the neighbour before to the
neighbour after: centres on the chord-length Catmull-Rom curve, radii the limited Hermite of
``motors``, normals the Hermite spline of the node normals) against the centreline of the
SPANS_AROUND spans on either side (SPAN_SAMPLES samples per span, the radius linear along each).
A ring point's bulge is its distance to the nearest sample over the radius there (the fidelity
measure of benchmarks/fidelity.py, restricted to the neighbourhood); the wall folds where a quad
between consecutive rings faces its ring's centre while others face away. Where the rings at
the bisector bulge beyond ENVELOPE_LIMIT or fold, the normal turns in the plane of the turn
(n(w) = (1 - w) u_in + w u_out normalised, w = 1/2 the bisector) by the least step of the grid
of TILT_STEPS that keeps the rings within the limit without folding; else, where the bisector's
rings reach beyond HARD_LIMIT, to the least bulge that does not fold; else not at all. Turning
towards the thin span's chord moves the ring's inner side back, off the thin span; it also
brings that side nearer the centreline before the node, so only nodes that need it turn (about
1.5% of a real neuron's nodes), and no further than needed. Nodes are decided in two passes
(even places along each chain, then odd ones against the even ones' final normals), so that
every span is measured with its two final ends. A coarse look (COARSE) spares the full measure
to most nodes, and nodes whose window of radii cannot give a bulge beyond the limit are not
measured (see ``envelope_normals``). docs/interpolation.md section 12 has the figures.

Every node is measured from its own neighbourhood alone, with the same operations whatever
other chains are processed with it, so the per-chain and the batched paths agree bit for bit.
"""

from __future__ import annotations

import numpy as np

from cgamesh.geometry.motors import monotone_slopes

# A node whose rings reach beyond this many radii of the centreline (see the module doc) turns.
ENVELOPE_LIMIT = 1.25
# Centreline samples per span, points per ring, rings measured on each of a node's two spans
# (the node's own among them).
SPAN_SAMPLES = 12
RING_POINTS = 16
RINGS_PER_SPAN = 8
FINE = (SPAN_SAMPLES, RING_POINTS, RINGS_PER_SPAN)
# The first, coarse look at every node (see ``_tilts``) and the bulge beyond which it flags a
# node for the full measure (a margin for what the coarse samples miss).
COARSE = (6, 8, 3)
COARSE_LIMIT = 1.1
# Rings at the bisector beyond this (the target no vertex may pass) turn to their least bulge
# even when no turn brings them within ENVELOPE_LIMIT.
HARD_LIMIT = 1.6
# Candidate weights w in [0, 1] (sixteenths).
TILT_STEPS = 17
# Spans of the centreline on each side of a node that its rings are measured against.
SPANS_AROUND = 2
# Distances computed at once (bounds the scratch memory: about 24 bytes each).
CHUNK_VALUES = 2_000_000
# Turns of less than this (radians) between the chords leave the ring as it is.
LEAST_TURN = 1e-3


def _hermite(p0, p1, m0, m1, length, s):
    """Points (N, S, 3) of cubic Hermite spans from p0 to p1 (N, 3) with slopes m0, m1 per unit
    length, knots ``length`` (N,) apart, at local parameters s (S,)."""
    s = s[None, :, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    scale = length[:, None, None]
    return h00 * p0[:, None] + h10 * scale * m0[:, None] + h01 * p1[:, None] + h11 * scale * m1[:, None]


def envelope_normals(p: np.ndarray, radii: np.ndarray, tangents: np.ndarray, first: np.ndarray,
                     count: np.ndarray) -> np.ndarray:
    """Node normals (n, 3): ``tangents`` (the bisectors), turned where a node ring would leave
    the radius envelope (see the module doc). p (n, 3) and radii (n,) of chains concatenated,
    chain k being nodes first[k] .. first[k] + count[k] - 1 (distinct consecutive points)."""
    n = len(p)
    out = tangents.copy()
    if n < 3:
        return out
    index = np.arange(n)
    chain_first = np.repeat(first, count)
    chain_last = chain_first + np.repeat(count, count) - 1
    inner = (index != chain_first) & (index != chain_last)
    if not inner.any():  # chains of two nodes only: no node has two spans to turn between
        return out
    chord = np.zeros_like(p)
    chord[:-1] = p[1:] - p[:-1]
    length = np.sqrt((chord * chord).sum(axis=1))
    length[chain_last] = 1.0
    unit = chord / length[:, None]
    # slopes of the centre curve per unit length: the mean of the unit chords, one-sided at ends
    slope = np.empty_like(p)
    slope[inner] = 0.5 * (unit[index[inner] - 1] + unit[inner])
    slope[chain_first] = unit[chain_first]
    slope[chain_last] = unit[chain_last - 1]
    radius_slope = _radius_slopes(radii, length, chain_first, chain_last)
    u_in, u_out = unit[np.maximum(index - 1, 0)], unit
    turn = np.sqrt((np.cross(u_in, u_out) ** 2).sum(axis=1))
    candidates = index[inner & (turn > LEAST_TURN)]
    position = candidates - chain_first[candidates]
    # even places along each chain first, against their neighbours' bisectors; then odd places,
    # against the even ones' final normals: every span then has its final two ends measured
    # together (by its odd end), so two turned neighbours cannot fold the span between them
    # A ring point x of a ring with centre c and radius r has a centreline sample within r (c
    # itself), so its nearest sample y is within r of it and its bulge r / rho(y) at most: a
    # node whose rings' largest radius (that of its own or a neighbour node) is within
    # ENVELOPE_LIMIT of the least radius of its centreline window cannot bulge beyond the
    # limit, and is measured only if a neighbour turned (its wall might then fold)
    window = np.stack([radii[np.clip(candidates + k, chain_first[candidates], chain_last[candidates])]
                       for k in range(-SPANS_AROUND, SPANS_AROUND + 1)], axis=1)
    rings_largest = window[:, SPANS_AROUND - 1:SPANS_AROUND + 2].max(axis=1)
    may_bulge = rings_largest > ENVELOPE_LIMIT * window.min(axis=1)
    turned_node = np.zeros(n, dtype=bool)
    for parity in (0, 1):
        near_turned = turned_node[np.maximum(candidates - 1, 0)] | turned_node[np.minimum(candidates + 1, n - 1)]
        node = candidates[(position % 2 == parity) & (may_bulge | near_turned)]
        weights = _tilts(p, radii, radius_slope, out, slope, length, u_in, u_out, chain_first, chain_last, node)
        turned = weights != 0.5
        node, w = node[turned], weights[turned][:, None]
        normal = (1.0 - w) * u_in[node] + w * u_out[node]
        normal /= np.sqrt((normal * normal).sum(axis=1))[:, None]
        # keep the side the bisector had (the motion's orientation rule reads it)
        sign = np.sign((normal * tangents[node]).sum(axis=1))
        out[node] = normal * np.where(sign == 0.0, 1.0, sign)[:, None]
        turned_node[node] = True
    return out


def _tilts(p, radii, radius_slope, tangents, slope, length, u_in, u_out, chain_first, chain_last,
           node) -> np.ndarray:
    """(N,) the weight w of each node's normal n(w) (1/2: the bisector): the least turn that brings
    its rings within ENVELOPE_LIMIT without folding the wall; else, where the bisector's rings
    reach beyond HARD_LIMIT, the least bulge of a wall that does not fold; else the bisector.
    Only nodes whose rings at the bisector bulge beyond ENVELOPE_LIMIT or fold are turned."""
    middle = TILT_STEPS // 2
    weights = np.linspace(0.0, 1.0, TILT_STEPS)
    chosen = np.full(node.size, middle)

    def measure(nodes, columns, resolution=FINE):
        return _rings(p, radii, radius_slope, tangents, slope, length, u_in, u_out, chain_first, chain_last, nodes,
                      weights[columns], resolution)

    # a coarse look at every node first (about a tenth of the work), with a margin, then the full
    # measure of the nodes it flags
    look = np.arange(node.size)
    bulge, folded = _chunked(lambda nodes, columns: measure(nodes, columns, COARSE), node, np.array([middle]), COARSE)
    look = look[(bulge[:, 0] > COARSE_LIMIT) | folded[:, 0]]
    bulge, folded = _chunked(measure, node[look], np.array([middle]))
    flag = (bulge[:, 0] > ENVELOPE_LIMIT) | folded[:, 0]
    look, at_bisector = look[flag], bulge[flag, 0]
    # the candidates in order of their turn from the bisector, two at a time, each node only
    # until one brings its rings within the limit without folding the wall
    tried = np.full((look.size, TILT_STEPS), np.inf)  # bulge of each candidate, inf where it folds
    pending = np.arange(look.size)
    for turn in range(1, middle + 1):
        if pending.size == 0:
            break
        columns = np.array([middle - turn, middle + turn])
        b, f = _chunked(measure, node[look[pending]], columns)
        tried[pending[:, None], columns[None, :]] = np.where(f, np.inf, b)
        within = ~f & (b <= ENVELOPE_LIMIT)
        done = within.any(axis=1)
        chosen[look[pending[done]]] = columns[np.argmax(within[done], axis=1)]
        pending = pending[~done]
    # none within the limit: the least bulge that does not fold, but only where the bisector's
    # rings reach beyond HARD_LIMIT (elsewhere a turn the model cannot show within the limit is
    # as likely to reach further in the tube as less far: the bisector stays)
    least = np.argmin(tried[pending], axis=1)
    better = (at_bisector[pending] > HARD_LIMIT) & (tried[pending, least] < at_bisector[pending])
    chosen[look[pending[better]]] = least[better]
    return weights[chosen]


def _chunked(measure, node: np.ndarray, columns: np.ndarray, resolution=None) -> tuple[np.ndarray, np.ndarray]:
    """``measure(nodes, columns)`` over ``node`` in chunks that bound the scratch memory."""
    span_samples, ring_points, rings_per_span = resolution or FINE
    step = max(1, CHUNK_VALUES // (columns.size * ring_points * (2 * rings_per_span + 1) * 2 * SPANS_AROUND
                                   * (span_samples + 1)))
    parts = [measure(node[k:k + step], columns) for k in range(0, node.size, step)]
    if not parts:
        return np.zeros((0, columns.size)), np.zeros((0, columns.size), dtype=bool)
    return np.concatenate([b for b, _ in parts]), np.concatenate([f for _, f in parts])


def _normal_span(tangents, length, first_of, last_of, node, candidate, s, before: bool) -> np.ndarray:
    """(N, W, S, 3) unit normals at local parameters s (S,) of the span before (or after) each
    node, the node's normal being ``candidate`` (N, W, 3), the others their ``tangents``."""
    n_node = candidate
    if before:
        a, b = node - 1, node  # the span from a to b; b is the node
        n_a, n_b = tangents[a][:, None].repeat(n_node.shape[1], axis=1), n_node
        span = length[a]
        secant = (n_b - n_a) / span[:, None, None]
        back = np.maximum(a - 1, 0)
        previous = np.where((a == first_of[a])[:, None, None], secant,
                            ((tangents[a] - tangents[back]) / length[back][:, None])[:, None])
        following = (tangents[node + 1][:, None] - n_node) / length[node][:, None, None]
        m_a, m_b = 0.5 * (previous + secant), 0.5 * (secant + following)
    else:
        a, b = node, node + 1
        n_a, n_b = n_node, tangents[b][:, None].repeat(n_node.shape[1], axis=1)
        span = length[a]
        secant = (n_b - n_a) / span[:, None, None]
        preceding = (n_node - tangents[node - 1][:, None]) / length[node - 1][:, None, None]
        ahead = np.minimum(b + 1, len(tangents) - 1)
        beyond = np.where((b == last_of[b])[:, None, None], secant,
                          ((tangents[ahead] - tangents[b]) / length[b][:, None])[:, None])
        m_a, m_b = 0.5 * (preceding + secant), 0.5 * (secant + beyond)
    t = s[None, None, :, None]
    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
    scale = span[:, None, None, None]
    h = (h00 * n_a[:, :, None] + h10 * scale * m_a[:, :, None] + h01 * n_b[:, :, None]
         + h11 * scale * m_b[:, :, None])
    return h / np.sqrt((h * h).sum(axis=3))[..., None]


def _hermite_scalar(v0, v1, m0, m1, length, s):
    """(N, S) cubic Hermite spans of scalars from v0 to v1 (N,) with slopes m0, m1 per unit length."""
    s = s[None, :]
    return ((2 * s**3 - 3 * s**2 + 1) * v0[:, None] + (s**3 - 2 * s**2 + s) * (length * m0)[:, None]
            + (-2 * s**3 + 3 * s**2) * v1[:, None] + (s**3 - s**2) * (length * m1)[:, None])


def _radius_slopes(radii, length, chain_first, chain_last) -> np.ndarray:
    """(n,) the motion's radius slopes per unit length at the nodes: Catmull-Rom slopes limited
    as Fritsch and Carlson prescribe (``motors.monotone_slopes``), one-sided at chain ends."""
    index = np.arange(len(radii))
    secant = np.zeros(len(radii))
    secant[:-1] = (radii[1:] - radii[:-1]) / length[:-1]
    secant[chain_last] = secant[np.maximum(chain_last - 1, 0)]
    before = np.where(index == chain_first, secant, secant[np.maximum(index - 1, 0)])
    after = secant
    return monotone_slopes(0.5 * (before + after), before, after)


def _rings(p, radii, radius_slope, tangents, slope, length, u_in, u_out, first_of, last_of, node,
           weights, resolution=None) -> tuple[np.ndarray, np.ndarray]:
    """(N, W) each: the largest bulge of the rings near each node (index array (N,)) when the
    node's normal is n(w) for each weight (W,), and whether their wall folds (see the module
    doc). The rings are those of the node's two spans, RINGS_PER_SPAN per span from the
    neighbour before to the neighbour after, measured against SPANS_AROUND spans either side."""
    span_samples, ring_points, rings_per_span = resolution or FINE
    s = np.linspace(0.0, 1.0, span_samples + 1)
    # the centreline: the two spans either side of the node (a span past a chain's end is
    # replaced by the end span, sampled twice)
    lines, line_radii = [], []
    for offset in range(-SPANS_AROUND, SPANS_AROUND):
        a = np.clip(node + offset, first_of[node], last_of[node] - 1)
        lines.append(_hermite(p[a], p[a + 1], slope[a], slope[a + 1], length[a], s))
        line_radii.append(radii[a][:, None] + (radii[a + 1] - radii[a])[:, None] * s)
    line, line_radius = np.concatenate(lines, axis=1), np.concatenate(line_radii, axis=1)  # (N, L, 3), (N, L)
    # rings at s = 0 .. 1 of the span before and 1/8 .. 1 of the span after, normals as the
    # motion splines them (``motors``): Hermite spans of the node normals with Catmull-Rom
    # slopes per unit chord, the neighbours' normals their bisectors; radii as the motion's
    before_s = np.arange(rings_per_span + 1) / rings_per_span
    after_s = before_s[1:]
    ring_centre = np.concatenate([
        _hermite(p[node - 1], p[node], slope[node - 1], slope[node], length[node - 1], before_s),
        _hermite(p[node], p[node + 1], slope[node], slope[node + 1], length[node], after_s)], axis=1)
    ring_radius = np.concatenate([
        _hermite_scalar(radii[node - 1], radii[node], radius_slope[node - 1], radius_slope[node], length[node - 1],
                        before_s),
        _hermite_scalar(radii[node], radii[node + 1], radius_slope[node], radius_slope[node + 1], length[node],
                        after_s)], axis=1)
    w = weights[None, :, None]
    candidate = (1.0 - w) * u_in[node][:, None] + w * u_out[node][:, None]  # (N, W, 3)
    candidate /= np.sqrt((candidate * candidate).sum(axis=2))[..., None]
    normal = np.concatenate([_normal_span(tangents, length, first_of, last_of, node, candidate, before_s, before=True),
                             _normal_span(tangents, length, first_of, last_of, node, candidate, after_s, before=False)],
                            axis=2)  # (N, W, R, 3)
    bend = (u_out - u_in)[node][:, None, None, :]
    across = bend - normal * (bend * normal).sum(axis=3, keepdims=True)
    across /= np.maximum(np.sqrt((across * across).sum(axis=3)), 1e-300)[..., None]
    side = np.cross(normal, across)
    angle = np.linspace(0.0, 2.0 * np.pi, ring_points, endpoint=False)
    ring = ring_centre[:, None, :, None, :] + ring_radius[:, None, :, None, None] * (
        np.cos(angle)[None, None, None, :, None] * across[:, :, :, None, :]
        + np.sin(angle)[None, None, None, :, None] * side[:, :, :, None, :])  # (N, W, R, K, 3)
    # squared distances |x - y|^2 = |x|^2 + |y|^2 - 2 x . y about the node's centre (small
    # numbers, so no cancellation); one matrix product per node, so each node's figures do not
    # depend on which other nodes are measured with it
    centre = p[node][:, None, None, None, :]
    x = ring - centre
    y = line - p[node][:, None, :]
    cross_term = np.matmul(x.reshape(len(node), -1, 3), y.transpose(0, 2, 1)).reshape(x.shape[:4] + (y.shape[1],))
    # the same sum and difference in place (the (N, W, R, K, L) temporaries were most of the time)
    square = np.add((x * x).sum(axis=4)[..., None], (y * y).sum(axis=2)[:, None, None, None, :])
    square -= np.multiply(cross_term, 2.0, out=cross_term)
    del cross_term
    nearest = np.argmin(square, axis=4)
    gap = np.sqrt(np.maximum(np.take_along_axis(square, nearest[..., None], axis=4)[..., 0], 0.0))
    rho = line_radius[np.arange(len(node))[:, None, None, None], nearest]
    # the wall folds where a quad between consecutive rings faces its ring's centre while others
    # face away (the benchmark's folded segments)
    around = np.roll(ring, -1, axis=3) - ring
    along = ring[:, :, 1:] - ring[:, :, :-1]
    facing_normal = np.cross(around[:, :, :-1], along)
    radial = ring[:, :, :-1] - ring_centre[:, None, :-1, None, :]
    facing = (facing_normal * radial).sum(axis=4)
    size = 1e-9 * np.sqrt((facing_normal * facing_normal).sum(axis=4) * (radial * radial).sum(axis=4))
    folded = np.any(facing > size, axis=(2, 3)) & np.any(facing < -size, axis=(2, 3))
    return (gap / rho).max(axis=(2, 3)), folded
