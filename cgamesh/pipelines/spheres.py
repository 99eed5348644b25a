"""The junction and soma spheres of a centreline input: which, how large, how many vertices around.

Branch nodes are closed by spheres of their radius (watertight: enlarged to enclose the tubes'
rings), a neuron's soma (SWC type 1 nodes) by spheres of its radius, meshed as UV spheres
(cgamesh.meshing.junctions) with their nodes' attributes. At a fixed resolution every sphere has
the run's count around; under a tolerance each has the fewest that keep it within the
tolerance (``spheres_around``; docs/tolerance.md, "Junction and soma spheres").
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace

import numpy as np

from cgamesh.errors import InvalidInputError
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.pipelines.tube_options import TubeOptions

SOMA_SEGMENT = -1.0  # the ``segment`` attribute of soma spheres


def sphere_meshes(junctions, points, radii, soma, scalar, tangents, segment_of, options, stem,
                  block: int | None = None) -> Iterator[SurfaceMesh]:
    """The junction spheres and the soma spheres, those that exist: one mesh per group and count
    around (one count at a fixed resolution; per sphere under a tolerance, ``spheres_around``),
    its spheres in node order.

    ``block``: the meshes of at most that many vertices (at least one sphere), made one at a time
    as they are asked for, so a run that merges them never holds more than one block beside the
    merged mesh (what a merge makes of consecutive blocks is the group's mesh: every sphere's
    vertices and values are its own)."""
    from cgamesh.meshing.junctions import sphere_bands

    for name, nodes, sphere_radii, around in sphere_groups(junctions, soma, radii, options):
        for count in np.flatnonzero(np.bincount(around)):  # the counts present (np.unique imports numpy.ma)
            chosen = np.flatnonzero(around == count)
            per_sphere = (count + 1) * (sphere_bands(int(count)) + 1)
            step = len(chosen) if block is None else max(1, block // per_sphere)
            for start in range(0, len(chosen), step):
                part = chosen[start:start + step]
                mesh = _sphere_mesh(name, nodes[part], sphere_radii[part], int(count), points, radii, scalar,
                                    tangents, segment_of, options, stem)
                yield from split_spheres(mesh, len(part)) if options.watertight else [mesh]


def sphere_groups(junctions, soma, radii, options: TubeOptions) -> Iterator[tuple]:
    """(name, nodes, radii, counts around) of the junction and of the soma spheres, those that
    exist: the radii enclosing the tubes' rings when watertight, the counts ``options.around``
    or, under a tolerance, each sphere's own (``spheres_around``)."""
    for name, nodes in (("junctions", junctions[~soma[junctions]]), ("soma", np.flatnonzero(soma))):
        if not len(nodes):
            continue
        sphere_radii = radii[nodes] * (junction_scale(options) if name == "junctions" else 1.0)
        if options.tolerance is None:
            around = np.full(len(nodes), options.around)
        else:
            around = spheres_around(sphere_radii, options.tolerance)
        yield name, nodes, sphere_radii, around


def _sphere_mesh(name, group, sphere_radii, around, points, radii, scalar, tangents, segment_of, options,
                 stem) -> SurfaceMesh:
    """UV spheres of ``around`` at the nodes ``group`` with their attributes and colours."""
    from cgamesh.meshing.junctions import uv_spheres

    mesh = uv_spheres(points[group], sphere_radii, around, name=f"{stem}_{name}")
    per = mesh.vertex_count // len(group)
    attributes = {"radius": np.repeat(radii[group], per), "segment": np.repeat(segment_of[group], per)}
    if name == "soma":
        attributes["segment"][:] = SOMA_SEGMENT
    if scalar is not None:
        attributes["scalar"] = np.repeat(scalar[group], per)
    colors = None
    if options.color_by == "direction":
        from cgamesh.meshing.colors import direction_colors

        colors = direction_colors(np.repeat(tangents[group], per, axis=0))
    return replace(mesh, attributes=attributes, colors=colors)


def split_spheres(mesh: SurfaceMesh, count: int) -> list[SurfaceMesh]:
    """A mesh of ``count`` equal spheres (``uv_spheres``) as one mesh per sphere: overlapping
    spheres must enter a union as separate solids, not as one self-overlapping mesh."""
    per_vertex, per_face = mesh.vertex_count // count, mesh.triangle_count // count
    out = []
    for k in range(count):
        rows = slice(k * per_vertex, (k + 1) * per_vertex)
        base = k * per_vertex
        out.append(SurfaceMesh(
            name=f"{mesh.name}_{k}", positions=mesh.positions[rows], normals=mesh.normals[rows], uvs=mesh.uvs[rows],
            faces=np.asarray(mesh.faces[k * per_face:(k + 1) * per_face]) - base,
            weld=None if mesh.weld is None else np.asarray(mesh.weld[rows]) - base,
            colors=None if mesh.colors is None else mesh.colors[rows],
            attributes=None if mesh.attributes is None else {n: a[rows] for n, a in mesh.attributes.items()}))
    return out


def junction_scale(options: TubeOptions) -> float:
    """The junction spheres' radius over their node's: watertight, they enclose the tubes' rings."""
    if not options.watertight:
        return 1.0
    from cgamesh.meshing.frusta import enclosing_sphere_scale

    return enclosing_sphere_scale(options.around)  # the tubes' rings there lie strictly inside


def spheres_around(radii: np.ndarray, tolerance: float) -> np.ndarray:
    """Per sphere the fewest vertices around whose UV sphere lies within ``tolerance`` of it
    (cgamesh.meshing.junctions.around_within), from one table of the bound over the counts up to
    the largest sphere's. InvalidInputError when a sphere needs more than junctions.MAX_AROUND."""
    from cgamesh.meshing.junctions import around_within, deviation_bound

    try:
        largest = around_within(float(radii.max()), tolerance)
    except ValueError as error:
        raise InvalidInputError(f"tolerance {tolerance:g} is too small for the junction and soma spheres: "
                                f"{error}") from None
    counts = np.arange(4, largest + 1)
    # the least bound up to each count: the fewest count meeting a bound is where this first does
    least = np.minimum.accumulate([deviation_bound(int(m)) for m in counts])
    return counts[np.searchsorted(-least, -tolerance / radii)]
