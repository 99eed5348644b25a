"""Checks every writer makes before it writes: shapes, index ranges, finite values, materials.

Format-neutral (no format's vocabulary here). The glTF writer folds its finiteness checks into
the reductions it computes anyway and so calls only ``check_shapes`` and ``check_material``;
the other writers call ``check_surfaces``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from cgamesh.errors import ExportError
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh

# Unit normals after a float32 cast are within ~1e-7 of length 1; an input normal further than
# this from unit length is a bug upstream (SurfaceMesh promises unit normals), not rounding.
NORMAL_LENGTH_TOLERANCE = 1e-3
UP_AXES = ("z", "y")
# Per-vertex attribute names: lower-case identifiers, so every format can name them (glTF
# upper-cases them after an underscore, USD primvars and PLY properties take them as they are).
ATTRIBUTE_NAME = re.compile(r"[a-z][a-z0-9_]*")
# Colours a mesh op interpolated may stray from [0, 1] by rounding; more than this is a bug.
COLOR_RANGE_SLACK = 1e-9
FLOAT32_MAX = float(np.finfo(np.float32).max)
LENGTH_BLOCK = 1 << 13  # rows of normals measured at a time (their float64 squares: 200 kB)


def check_arguments(path, surfaces: Sequence, up: str, meters_per_unit: float) -> float:
    """The scene-wide arguments of every writer; returns meters_per_unit as a float."""
    if up not in UP_AXES:
        raise ExportError(f"cannot export {path}: up must be 'z' or 'y', got {up!r}")
    scale = float(meters_per_unit)
    if not (np.isfinite(scale) and scale > 0.0):
        raise ExportError(f"cannot export {path}: meters_per_unit must be finite and > 0, got {meters_per_unit!r}")
    if len(surfaces) == 0:
        raise ExportError(f"cannot export {path}: no surfaces to write")
    return scale


def check_shapes(mesh: SurfaceMesh, path) -> None:
    """Shapes, integer faces and index ranges of one mesh (not the values)."""
    v = mesh.vertex_count
    where = f"cannot export {path}: surface {mesh.name!r}"
    expected = {"positions": (v, 3), "normals": (v, 3), "uvs": (v, 2)}
    if mesh.tangents is not None:
        expected["tangents"] = (v, 4)
    for name, shape in expected.items():
        got = np.shape(getattr(mesh, name))
        if got != shape:
            raise ExportError(f"{where}: {name} must have shape {shape}, got {got}")
    if np.ndim(mesh.faces) != 2 or np.shape(mesh.faces)[1] != 3:
        raise ExportError(f"{where}: faces must have shape (F, 3), got {np.shape(mesh.faces)}")
    if v == 0 or mesh.triangle_count == 0:
        raise ExportError(f"{where}: empty mesh ({v} vertices, {mesh.triangle_count} triangles)")
    if not np.issubdtype(np.asarray(mesh.faces).dtype, np.integer):
        raise ExportError(f"{where}: faces must be integers, got {np.asarray(mesh.faces).dtype}")
    lo, hi = int(mesh.faces.min()), int(mesh.faces.max())
    if lo < 0 or hi >= v:
        raise ExportError(f"{where}: face indices must be in [0, {v - 1}], got [{lo}, {hi}]")


class Measured(NamedTuple):
    """What the checks measure of a mesh, for writers that need it: position bounds (2, 3) and
    normal lengths (V,)."""

    bounds: np.ndarray
    normal_lengths: np.ndarray


def check_values(mesh: SurfaceMesh, path) -> Measured:
    """Finite positions and UVs, finite unit normals; returns what was measured on the way."""
    where = f"cannot export {path}: surface {mesh.name!r}"
    bounds = {}
    for name in ("positions", "uvs"):
        bounds[name] = column_bounds(np.asarray(getattr(mesh, name), dtype=np.float64))
        if not np.isfinite(bounds[name]).all():
            raise ExportError(f"{where}: {name} contain NaN or infinity")
        # Files store them in float32 (PLY, STL, USD): beyond its range they would be infinities.
        if np.abs(bounds[name]).max() > FLOAT32_MAX:
            raise ExportError(f"{where}: {name} exceed float32's range (largest "
                              f"{np.abs(bounds[name]).max():.3g}); no output can store them")
    return Measured(bounds["positions"], normal_lengths(mesh, path))


def normal_lengths(mesh: SurfaceMesh, path) -> np.ndarray:
    """|normal| (V,), after checking each is within NORMAL_LENGTH_TOLERANCE of 1 (NaN fails too)."""
    length = vector_lengths(np.asarray(mesh.normals))
    _check_unit(mesh, path, length, 0)
    return length


def normal_length_error(mesh: SurfaceMesh, path) -> float:
    """The largest ||normal| - 1| after the check of ``normal_lengths``, measured a block of
    rows at a time (no array of V lengths held)."""
    normals = np.asarray(mesh.normals)
    largest = 0.0
    for start in range(0, len(normals), LENGTH_BLOCK):
        length = vector_lengths(normals[start:start + LENGTH_BLOCK])
        _check_unit(mesh, path, length, start)
        largest = max(largest, float(np.abs(length - 1.0).max(initial=0.0)))
    return largest


def _check_unit(mesh: SurfaceMesh, path, length: np.ndarray, first: int) -> None:
    """ExportError naming the first vertex whose normal (length ``length[k]``, vertex
    ``first + k``) is not unit within NORMAL_LENGTH_TOLERANCE (NaN fails too)."""
    bad = ~(np.abs(length - 1.0) <= NORMAL_LENGTH_TOLERANCE)  # NaN compares False: caught too
    if bad.any():
        k = first + int(np.argmax(bad))
        raise ExportError(f"cannot export {path}: surface {mesh.name!r}: normals must be finite unit vectors, "
                          f"vertex {k} has {np.asarray(mesh.normals[k], dtype=np.float64).tolist()}")


def vector_lengths(vectors: np.ndarray) -> np.ndarray:
    """|v| (n,) in float64 of vectors (n, 3) of any float type. Shared by the writers' checks and the merge that
    holds normals as the glTF writer stores them (cgamesh.meshing.merge): a row's length does
    not depend on the rows around it (the product below sums each row's three squares in one
    order whatever the block; measured on millions of rows at every alignment)."""
    # Squares summed by a matrix-vector product: several times faster than einsum's loop
    # over a last axis of 3 (and 3x faster than adding strided columns); a block of rows at a
    # time, so the squares never take 3 arrays of V.
    length = np.empty(len(vectors))
    for start in range(0, len(vectors), LENGTH_BLOCK):
        rows = slice(start, start + LENGTH_BLOCK)
        np.sqrt(np.square(np.asarray(vectors[rows], dtype=np.float64)) @ np.ones(3), out=length[rows])
    return length


def check_channels(mesh: SurfaceMesh, path) -> None:
    """The optional per-vertex channels: colours (V, 3) finite in [0, 1] (linear RGB), and
    attributes (V,) under lower-case identifiers, finite and within float32's range (every
    format stores them as float32)."""
    v = mesh.vertex_count
    where = f"cannot export {path}: surface {mesh.name!r}"
    if mesh.colors is not None:
        colors = np.asarray(mesh.colors)
        if colors.shape != (v, 3):
            raise ExportError(f"{where}: colors must have shape {(v, 3)}, got {colors.shape}")
        bounds = column_bounds(colors)  # float32 colours (cgamesh.meshing.merge) compare exactly
        if not (np.isfinite(bounds).all() and bounds.min() >= -COLOR_RANGE_SLACK
                and bounds.max() <= 1.0 + COLOR_RANGE_SLACK):
            raise ExportError(f"{where}: colors must be finite linear RGB in [0, 1], got values in "
                              f"[{bounds.min()}, {bounds.max()}]")
    for name, values in (mesh.attributes or {}).items():
        if not isinstance(name, str) or ATTRIBUTE_NAME.fullmatch(name) is None:
            raise ExportError(f"{where}: attribute names must be lower-case identifiers "
                              f"([a-z][a-z0-9_]*), got {name!r}")
        values = np.asarray(values)
        if values.shape != (v,):
            raise ExportError(f"{where}: attribute {name!r} must have shape {(v,)}, got {values.shape}")
        if not np.issubdtype(values.dtype, np.number):
            raise ExportError(f"{where}: attribute {name!r} must be numbers, got {values.dtype}")
        # NaN propagates through min and max (and shows in the largest), no array of V made
        largest = float(np.abs([values.min(), values.max()]).max()) if len(values) else 0.0
        if not largest <= FLOAT32_MAX:
            k = int(np.argmax(~(np.abs(values) <= FLOAT32_MAX)))
            raise ExportError(f"{where}: attribute {name!r} must be finite and within float32's range, "
                              f"vertex {k} has {values[k]}")


def check_material(mesh: SurfaceMesh, material: Material, path) -> None:
    values = [*material.color, material.metallic, material.roughness]
    if len(material.color) != 3 or not all(np.isfinite(x) and 0.0 <= x <= 1.0 for x in values):
        raise ExportError(
            f"cannot export {path}: surface {mesh.name!r}: material color, metallic and roughness "
            f"must be in [0, 1], got {material}"
        )


def check_surfaces(path, surfaces: Sequence[tuple[SurfaceMesh, Material]], up: str,
                   meters_per_unit: float) -> tuple[float, list[Measured]]:
    """Everything above for every surface, and unique names; returns meters_per_unit and what
    was measured of each mesh (so writers need not measure it again)."""
    scale = check_arguments(path, surfaces, up, meters_per_unit)
    seen = set()
    measured = []
    for mesh, material in surfaces:
        if mesh.name in seen:
            raise ExportError(f"cannot export {path}: two surfaces are named {mesh.name!r}")
        seen.add(mesh.name)
        check_shapes(mesh, path)
        measured.append(check_values(mesh, path))
        check_material(mesh, material, path)
        check_channels(mesh, path)
    return scale, measured


def column_bounds(a: np.ndarray) -> np.ndarray:
    """(2, k) per-column minimum and maximum of an (n, k) array.

    Column by column because numpy's axis-0 reduction over a narrow (n, 3) array is ~20x
    slower than k strided 1-d reductions. NaN propagates through min / max and an infinity
    shows in them, so finite bounds also prove the whole array finite, with no extra pass.
    """
    return np.array([[a[:, j].min() for j in range(a.shape[1])], [a[:, j].max() for j in range(a.shape[1])]])
