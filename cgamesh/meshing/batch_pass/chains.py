"""Centreline chains at a fixed resolution: every chain's tube, all chains at once.

``tube_pieces`` does for every chain what ``pipelines.tubes`` does for one (soma radii, exact
duplicates merged, node tangents and ring normals, the chain's local frame, the motion, the
mesh, its attributes and direction colours, the junction bookkeeping), as arrays over every
chain. A chain with nodes inside the soma takes its nodes' radii outside it
(``_outside_radii``); one entirely inside has no tube (the soma's spheres stand for it); one of
fewer than two distinct points, or whose tube cannot be meshed (``rings``), is skipped with its
error. Chains are meshed in chunks of about CHUNK_RINGS rings, so scratch memory stays bounded
and progress is reported per chunk.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cgamesh.budget import BATCHED_CHUNK_RINGS
from cgamesh.errors import DegenerateGeometryError
from cgamesh.geometry.motors import MotionNodes, Motions
from cgamesh.meshing.batch_pass.rings import TubeArrays, mesh_chains
from cgamesh.meshing.circles import grid_weld
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.node_normals import envelope_normals

# Rings meshed per chunk: the circle blades and their products (about 3 kB per ring) stay
# within a core's cache (measured: 2,048 rings ~25% faster than 16,384 on the fornix); the
# memory budget prices a batched run by it.
CHUNK_RINGS = BATCHED_CHUNK_RINGS
SOMA_SEGMENT = -1.0


def _segment_tangents(p: np.ndarray, first: np.ndarray, count: np.ndarray) -> np.ndarray:
    """``pipelines.tubes.node_tangents`` of every chain (p concatenated, >= 2 points each)."""
    n = len(p)
    index = np.arange(n)
    chain_first = np.repeat(first, count)
    chain_last = chain_first + np.repeat(count, count) - 1
    is_first, is_last = index == chain_first, index == chain_last
    nxt, prev = np.minimum(index + 1, n - 1), np.maximum(index - 1, 0)
    forward = p[nxt] - p  # node i's outgoing chord (meaningless at a chain's last node)
    unit = forward / np.where(is_last, 1.0, np.linalg.norm(forward, axis=1))[:, None]
    t = np.empty_like(p)
    t[is_first] = unit[is_first]
    t[is_last] = unit[prev[is_last]]
    middle = ~is_first & ~is_last
    t[middle] = unit[prev[middle]] + unit[middle]
    length = np.linalg.norm(t, axis=1)
    back = middle & (length <= 1e-12)
    t[back] = unit[prev[back]]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def _outside_radii(node_radii: np.ndarray, inside: np.ndarray, chain_first: np.ndarray,
                   chain_last: np.ndarray) -> np.ndarray:
    """The radii ``pipelines.tubes.tube_spec`` gives a chain's nodes (concatenated, before
    duplicates merge) when some lie inside the soma: each node inside takes the radius of the
    nearest node of its chain outside (the earlier of two as near, as argmin picks), so a
    neurite leaving the soma starts with its own radius. ``inside``: nodes to replace, only of
    chains with a node outside; ``chain_first`` / ``chain_last``: each node's chain's ends."""
    if not inside.any():
        return node_radii
    n = len(node_radii)
    index = np.arange(n)
    before = np.maximum.accumulate(np.where(inside, -1, index))  # the last node outside so far
    after = np.minimum.accumulate(np.where(inside, n, index)[::-1])[::-1]  # the next one outside
    has_before, has_after = before >= chain_first, after <= chain_last
    source = np.where(has_after & (~has_before | (after - index < index - before)), after, before)
    out = node_radii.copy()
    out[inside] = node_radii[source[inside]]
    return out


def _interp(values: np.ndarray, first: np.ndarray, count: np.ndarray, chain: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``np.interp(s, arange(count), values[chain's nodes])`` for every vertex, with numpy's formula."""
    last = count[chain] - 1
    j = np.minimum(np.floor(s).astype(np.int64), np.maximum(last - 1, 0))
    base = first[chain] + j
    at = values[base]
    slope = values[np.minimum(base + 1, first[chain] + last)] - at
    out = slope * (s - j) + at
    end = s >= last
    out[end] = values[(first[chain] + last)[end]]
    return out


def tube_pieces(chains, points, radii, soma, scalar, tangents, segment_of, options, stem: str, label_name,
                progress: Callable, sink: Callable[[SurfaceMesh], None]) -> list[str]:
    """Hands the tube meshes of ``chains`` to ``sink`` in chain order (runs of batched chains as
    one mesh each, unless ``options.split``), chunk by chunk, so a caller that merges them holds
    one chunk's pieces at a time; returns the skipped chains' lines. Updates ``tangents`` and
    ``segment_of`` (the junction spheres' direction and segment) as the per-chain loop does.
    ``chains``: every chain's nodes as one flat array (``nodes``, ``offsets``, ``counts``);
    ``chains[i]`` is chain i with its label, made only for messages and names."""
    counts = chains.counts
    total = len(chains)
    nodes = chains.nodes[chains.offsets[0]:chains.offsets[-1]]
    chain_of = np.repeat(np.arange(total), counts)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    inside = np.bincount(chain_of, weights=soma[nodes], minlength=total)
    soma_only = inside == counts
    mixed = (inside > 0) & ~soma_only
    p = points[nodes]
    distinct = np.ones(len(nodes), dtype=bool)
    distinct[1:] = np.any(p[1:] != p[:-1], axis=1)
    distinct[first[counts > 0]] = True
    kept_counts = np.bincount(chain_of[distinct], minlength=total)
    meshable = ~soma_only & (kept_counts >= 2)
    # per-node arrays of the distinct nodes of meshable chains
    take = distinct & meshable[chain_of]
    m_nodes, m_chain = nodes[take], chain_of[take]
    m_count = kept_counts * meshable
    m_first = np.concatenate([[0], np.cumsum(m_count)[:-1]]).astype(np.int64)
    m_p = points[m_nodes]
    m_r = _outside_radii(radii[nodes], soma[nodes] & mixed[chain_of], first[chain_of],
                         (first + counts - 1)[chain_of])[take]
    m_t = (envelope_normals(m_p, m_r, _segment_tangents(m_p, m_first[meshable], m_count[meshable]),
                            m_first[meshable], m_count[meshable]) if len(m_p) else np.zeros((0, 3)))

    rings_of = (m_count - 1) * (options.subdivide + 1) + 1
    # chunks of about CHUNK_RINGS rings of meshable chains; a chain without a tube joins the
    # chunk it falls in by index, so pieces come out in chain order chunk after chunk
    chunk_of = np.cumsum(np.where(meshable, rings_of, 0)) // CHUNK_RINGS
    bounds = np.flatnonzero(np.diff(chunk_of)) + 1
    skipped: list[tuple[int, str]] = []
    meshed = meshable.copy()
    for chunk in np.split(np.arange(total), bounds) if total else []:
        members = chunk[meshable[chunk]]
        errors = {int(index): DegenerateGeometryError(f"{chains.location(index)}: expected at least two distinct "
                                                      f"points, got {kept_counts[index]}")
                  for index in chunk[~meshable[chunk] & ~soma_only[chunk]]}
        batched_meshes: dict[int, SurfaceMesh] = {}
        if len(members):
            result = _mesh_chunk(members, m_first, m_count, m_p, m_t, m_r, options, stem)
            errors.update({int(members[k]): type(error)(f"{chains.location(members[k])}: {error}")
                           for k, error in result.errors.items()})
            batched_meshes = _chain_meshes(members, result, m_first, m_count, m_p, m_r, m_t, scalar, m_nodes,
                                           chains, options, stem, label_name)
            del result  # the chunk's scratch arrays, freed before the next chunk
            progress(chains[int(members[-1])].label, len(members))
        for index in sorted(errors):
            if options.strict:
                raise errors[index]
            skipped.append((index, str(errors[index])))
            meshed[index] = False
        for index in chunk[~meshable[chunk]]:  # chains without a tube, counted one by one
            progress(chains[int(index)].label, 1)
        for key in sorted(batched_meshes):
            sink(batched_meshes[key])
    _junction_events(meshed, m_first, m_count, m_nodes, m_t, tangents, segment_of)
    return [line for _, line in sorted(skipped)]


def chain_motions(centre: np.ndarray, tangent: np.ndarray, radius: np.ndarray, first: np.ndarray,
                  count: np.ndarray) -> tuple[Motions, np.ndarray, np.ndarray]:
    """The splined motions of chains through their node circles (centres, ring normals of any
    length (N, 3), radii (N,), file units; chain c's nodes are first[c] .. first[c] + count[c] - 1)
    in each chain's working frame, with the frames' origins (C, 3) and scales (C,): each frame
    ``LocalFrame.enclosing`` of its chain's centres and radii, each normal over its own length."""
    chain = np.repeat(np.arange(len(count)), count)
    low = np.minimum.reduceat(centre, first, axis=0)
    high = np.maximum.reduceat(centre, first, axis=0)
    origin = 0.5 * (low + high)
    reach = np.linalg.norm(centre - origin[chain], axis=1) + radius
    scale = np.maximum.reduceat(reach, first)
    scale = np.where(scale > 0.0, scale, 1.0)
    local_centre = (centre - origin[chain]) / scale[chain][:, None]
    # each control's normal / np.linalg.norm(normal) of its 3-vector (a dot product): matmul
    # of the 1 x 3 rows rounds as that does, the row-wise norm does not
    normal = tangent / np.sqrt(np.matmul(tangent[:, None, :], tangent[:, :, None])[:, 0])
    motions = Motions.through(local_centre, normal, radius / scale[chain], MotionNodes(first, count), "catmull_rom")
    return motions, origin, scale


def _mesh_chunk(members, first, count, p, t, r, options, stem: str) -> TubeArrays:
    """The batched meshes of the chains ``members`` (indices into the per-chain arrays)."""
    c = count[members]
    local_first = np.concatenate([[0], np.cumsum(c)[:-1]]).astype(np.int64)
    index = np.repeat(first[members] - local_first, c) + np.arange(int(c.sum()))
    motions, origin, scale = chain_motions(p[index], t[index], r[index], local_first, c)
    return mesh_chains(motions, origin, scale, options.around, options.subdivide,
                       [f"{stem}_{int(index)}" for index in members])


def _junction_events(meshed, first, count, nodes, t, tangents, segment_of) -> None:
    """What the per-chain loop leaves in ``tangents`` / ``segment_of`` at chain ends: a chain's
    last node takes its index and end tangent; a first node keeps the earliest chain's unless a
    chain ends there."""
    chains = np.flatnonzero(meshed)
    if not len(chains):
        return
    ends = first[chains] + count[chains] - 1
    # earliest starting chain per node: assign in reverse order so the earliest wins
    order = chains[::-1]
    s_nodes = nodes[first[order]]
    tangents[s_nodes] = t[first[order]]
    segment_of[s_nodes] = order
    tangents[nodes[ends]] = t[ends]
    segment_of[nodes[ends]] = chains


def _chain_meshes(members, result: TubeArrays, first, count, p, radii, t, scalar, nodes, chains, options, stem,
                  label_name) -> dict[int, SurfaceMesh]:
    """Runs of consecutive chains (or, split, single chains) of one chunk as meshes, by first chain.

    A run's mesh carries no ``uv_lengths``: it goes into the merged mesh, which keeps none
    (cgamesh.meshing.merge); a single chain's are its two lengths broadcast over its vertices,
    as the per-chain mesher gives them."""
    failed = np.zeros(len(members), dtype=bool)
    failed[list(result.errors)] = True
    keep = np.flatnonzero(~failed)
    if not len(keep):
        return {}
    columns = options.around + 1
    # every vertex of a ring has the ring's values: they are computed once per ring, then repeated
    ring_chain = members[result.ring_chain]
    ring_s = result.ring_local / (options.subdivide + 1)
    for k in np.flatnonzero(result.dropped & ~failed):
        # rings left out as coincident: each ring's place along the chain from its arc length (v)
        # matched to the nodes' along the polyline
        rings = np.flatnonzero(result.ring_chain == k)
        c = members[k]
        nodes_p = p[first[c]: first[c] + count[c]]
        length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(nodes_p, axis=0), axis=1))])
        v = np.clip(result.uvs[rings * columns, 1], 0.0, 1.0)
        ring_s[rings] = np.interp(v * length[-1], length, np.arange(count[c]))
    attributes = {"radius": np.repeat(_interp(radii, first, count, ring_chain, ring_s), columns),
                  "segment": np.repeat(ring_chain.astype(np.float64), columns)}
    if scalar is not None:
        attributes["scalar"] = np.repeat(_interp(scalar[nodes], first, count, ring_chain, ring_s), columns)
    colors = None
    if options.color_by == "direction":
        from cgamesh.meshing.colors import direction_colors

        global_chain = np.repeat(ring_chain, columns)
        s = np.repeat(ring_s, columns)
        along_t = np.stack([_interp(t[:, k], first, count, global_chain, s) for k in range(3)], axis=1)
        del global_chain, s
        colors = direction_colors(along_t)  # any length; a zero one (a turn back) gets NAN_COLOR
        del along_t
    vertex_counts = np.bincount(result.ring_chain, minlength=len(members)) * columns
    v_start = np.concatenate([[0], np.cumsum(vertex_counts)])
    f_start = np.concatenate([[0], np.cumsum(result.face_counts)])
    if options.split:
        groups = [[k] for k in keep]
    else:  # runs of chains with consecutive indices
        breaks = np.flatnonzero(np.diff(members[keep]) != 1) + 1
        groups = np.split(keep, breaks)
    strip = 2 * options.around  # triangles between two consecutive rings
    out = {}
    for group in groups:
        lo, hi = int(group[0]), int(group[-1])
        vs, ve, fs, fe = v_start[lo], v_start[hi + 1], f_start[lo], f_start[hi + 1]
        if options.split:
            faces = result.faces[fs:fe]
            weld = grid_weld(vertex_counts[lo] // columns, options.around, False)
            name = f"{stem}_{label_name(chains[int(members[lo])].label)}"
            uv_lengths = np.broadcast_to(result.uv_lengths[lo], (ve - vs, 2))
        else:  # each chain's local indices shifted, in place, by its first vertex in the run (per ring pair)
            faces = result.faces[fs:fe]
            shift = np.repeat(v_start[lo:hi + 1] - vs, result.face_counts[lo:hi + 1] // strip).astype(np.int32)
            faces.reshape(-1, strip, 3)[...] += shift[:, None, None]
            weld = uv_lengths = None
            name = stem
        out[int(members[lo])] = SurfaceMesh(
            name=name, positions=result.positions[vs:ve], normals=result.normals[vs:ve], uvs=result.uvs[vs:ve],
            faces=faces, uv_lengths=uv_lengths, weld=weld,
            colors=None if colors is None else colors[vs:ve],
            attributes={key: value[vs:ve] for key, value in attributes.items()})
    return out
