"""USD export through usd-core (pxr): .usda (text), .usdc and .usd (binary crate), .usdz (package).

USD's own vocabulary stays inside this file; pxr is imported only when a USD file is written.

Stage: ``upAxis`` and ``metersPerUnit`` are the scene file's (USD carries them, so there is no
axis swap and no scaling; the one exception is a z-up scene written as .usdz, whose ARKit rules
require upAxis Y: see ``build_stage``); ``defaultPrim`` is one Xform named after the output file (``Scene``
when its stem is not a valid prim name), holding one ``UsdGeom.Mesh`` per surface, named after
it, and a ``Materials`` scope with one ``UsdPreviewSurface`` material per surface, bound to its
mesh. The layer's customLayerData records the source units and up axis.

Meshes: ``subdivisionScheme = "none"`` (otherwise renderers treat the cage as a subdivision
surface and ignore the normals), right-handed orientation (triangles are counter-clockwise
seen from their normals), ``extent``, and points stored as float32 relative to a
``xformOp:translate`` (the double-precision centre of the bounding box), which keeps float32's
precision for the surface's size. Points are welded: vertices the mesher repeated at a UV seam
or a cap rim (``SurfaceMesh.weld``, or bit-identical positions when a mesh has no weld map)
become one point, so the mesh is watertight where the surface is. ``primvars:normals`` and
``primvars:st`` are then "vertex" when every welded point has one value, and indexed
"faceVarying" otherwise (st across a UV seam, normals around a cap's rim), so no value is
lost or averaged. st is the scene's UV as it is (USD's st origin is bottom-left, like ours).
``doubleSided`` is set for double-sided surfaces (ribbons).

Per-vertex channels, when a mesh has them, follow the same rule ("vertex" on the welded points
where the repeated vertices agree, indexed "faceVarying" otherwise): colours as
``primvars:displayColor`` (color3f[], linear RGB, USD's own colour primvar) and each attribute
as a float[] primvar of its name (``radius`` -> ``primvars:radius``), for shaders to read.

.usdz: the crate file is written to scratch space (memory when there is a /dev/shm) and
packaged as the usdz specification requires (``cgamesh.export.usdz``: uncompressed, 64-byte
aligned, the layout usd-core's own Sdf.ZipFileWriter produces, in a fraction of its time).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cgamesh.errors import ExportError
from cgamesh.export.atomic import atomic_path, atomic_write
from cgamesh.export.checks import Measured, check_surfaces
from cgamesh.export.options import WriteOptions
from cgamesh.export.usdz import PackageTooLargeError, write_package
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.meshing.weld import weld_by_position

SUFFIXES = (".usda", ".usdc", ".usd", ".usdz")
# Normals this close to unit length round to the same float32 vectors whether or not they are
# divided by their length first.
UNIT_ENOUGH = 1e-12
MATERIALS_SCOPE = "Materials"
# Primvars this writer (or UsdGeom) defines itself: per-vertex attributes may not take these names.
RESERVED_PRIMVARS = ("normals", "st", "displayColor", "displayOpacity")


def write_usd(
    path: str | os.PathLike[str],
    surfaces: Sequence[tuple[SurfaceMesh, Material]],
    options: WriteOptions,
) -> int:
    """Write every (mesh, material) pair into one USD file at ``path``; returns its size in bytes.

    The format follows the suffix (.usda, .usdc, .usd, .usdz); of ``options`` it reads the
    shared part (up axis, unit). Raises ExportError (leaving any existing file
    untouched) for inconsistent meshes or a file that cannot be written, and
    MissingDependencyError when usd-core is not installed.
    """
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in SUFFIXES:
        raise ExportError(f"cannot export {path}: a USD file ends in one of {', '.join(SUFFIXES)}, got {suffix!r}")
    scale, measured = check_surfaces(path, surfaces, options.up, options.meters_per_unit)
    pxr = _pxr()
    stage = build_stage(pxr, surfaces, up=options.up, meters_per_unit=scale, source_units=options.source_units,
                        root=_root_name(pxr, target), y_up=suffix == ".usdz", measured=measured,
                        arkit=suffix == ".usdz")
    layer = stage.GetRootLayer()
    if suffix == ".usdz":
        with tempfile.TemporaryDirectory(prefix="cgamesh-usdz-", dir=_scratch_dir()) as folder:
            crate = Path(folder) / f"{_root_name(pxr, target)}.usdc"
            _export(layer, crate, target)
            with atomic_write(target) as archive:
                try:
                    write_package(crate, archive, crate.name)
                except PackageTooLargeError as exc:
                    raise ExportError(f"cannot write {target}: {exc}; write .usdc instead") from None
                size = archive.tell()
    else:
        with atomic_path(target) as tmp:
            _export(layer, tmp, target)
            size = tmp.stat().st_size  # the target is renamed into place later in a multi-output commit
    return size


def point_count(surfaces: Sequence[tuple[SurfaceMesh, Material]]) -> int:
    """The points a USD file of these surfaces holds: each mesh's vertices welded by position
    (the seam column and cap rims repeat vertices that glTF keeps apart)."""
    return sum(len(welded(mesh)[0]) for mesh, _ in surfaces)


def _scratch_dir() -> str | None:
    """Where the crate file inside a .usdz is written first: memory (/dev/shm) when there is
    one, so packaging reads it back from RAM; else the system's temporary folder."""
    shm = "/dev/shm"
    return shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else None


def _export(layer, where: Path, target: Path) -> None:
    try:
        ok = layer.Export(str(where))
    except Exception as exc:  # pxr raises its own Tf.ErrorException
        raise ExportError(f"cannot write {target}: {' '.join(str(exc).split())}") from None
    if not ok:
        raise ExportError(f"cannot write {target}: usd-core could not write the layer")


class _Pxr:
    """The pxr modules this writer uses, imported together once."""

    def __init__(self) -> None:
        from cgamesh.optional import require

        require("pxr", "usd", "USD export")
        from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

        self.Gf, self.Sdf, self.Usd, self.UsdGeom, self.UsdShade, self.Vt = Gf, Sdf, Usd, UsdGeom, UsdShade, Vt


_PXR: _Pxr | None = None


def _pxr() -> _Pxr:
    global _PXR
    if _PXR is None:
        _PXR = _Pxr()
    return _PXR


def _root_name(pxr: _Pxr, target: Path) -> str:
    stem = target.stem
    return stem if pxr.Sdf.Path.IsValidIdentifier(stem) else "Scene"


def build_stage(pxr: _Pxr, surfaces, *, up: str, meters_per_unit: float, source_units: str, root: str,
                measured: list[Measured], y_up: bool = False, arkit: bool = False):
    """An in-memory stage holding every surface (see the module docstring).

    ``measured``: each mesh's bounds and normal lengths, as ``check_surfaces`` measured them.

    ``arkit``: only shaders the ARKit rules allow (a .usdz): vertex colours are then not wired
    into the material (see ``_define_material``).

    ``y_up``: the stage must be +Y up (a .usdz, by the ARKit rules); a z-up scene then gets
    upAxis Y and a -90 degree rotation about X on the default prim, mapping (x, y, z) to
    (x, z, -y) as the glTF export does, with the points themselves unchanged.
    """
    Sdf, Usd, UsdGeom, UsdShade = pxr.Sdf, pxr.Usd, pxr.UsdGeom, pxr.UsdShade
    stage = Usd.Stage.CreateInMemory()
    rotate = y_up and up == "z"
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z if up == "z" and not rotate else UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, float(meters_per_unit))
    stage.GetRootLayer().customLayerData = {
        "cgamesh": {"source_units": source_units, "meters_per_unit": float(meters_per_unit), "source_up": up}}
    root_path = Sdf.Path.absoluteRootPath.AppendChild(root)
    root_xform = UsdGeom.Xform.Define(stage, root_path)
    if rotate:
        root_xform.AddRotateXOp().Set(-90.0)
    root_prim = root_xform.GetPrim()
    stage.SetDefaultPrim(root_prim)
    Usd.ModelAPI(root_prim).SetKind("component")
    names = {mesh.name for mesh, _ in surfaces}
    scope_name = MATERIALS_SCOPE
    while scope_name in names:
        scope_name = "_" + scope_name
    scope = UsdGeom.Scope.Define(stage, root_path.AppendChild(scope_name)).GetPath()
    for (mesh, material), measures in zip(surfaces, measured):
        usd_mesh = _define_mesh(pxr, stage, root_path.AppendChild(mesh.name), mesh, measures)
        usd_material = _define_material(pxr, stage, scope.AppendChild(mesh.name), material,
                                        vertex_colors=mesh.colors is not None and not arkit)
        binding = UsdShade.MaterialBindingAPI.Apply(usd_mesh.GetPrim())
        binding.Bind(usd_material)
    return stage


def welded(mesh: SurfaceMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(keep, point_of, repeated): the vertices kept as points (P,), each vertex's point index
    (V,) int32, and the vertices that repeat an earlier one (R,)."""
    weld = mesh.weld if mesh.weld is not None else weld_by_position(mesh.positions)
    weld = np.asarray(weld)
    v = mesh.vertex_count
    own = weld == np.arange(v, dtype=weld.dtype)
    repeated = np.flatnonzero(~own)
    # A kept vertex's point is the number of kept vertices before it; a repeated vertex takes
    # the point of the one it repeats (weld[i] < i, and that one is kept).
    point_of = np.cumsum(own, dtype=np.int32)
    point_of -= 1
    point_of[repeated] = point_of[weld[repeated]]
    return np.flatnonzero(own), point_of, repeated


def _define_mesh(pxr: _Pxr, stage, prim_path, mesh: SurfaceMesh, measured: Measured):
    Gf, Sdf, UsdGeom, Vt = pxr.Gf, pxr.Sdf, pxr.UsdGeom, pxr.Vt
    positions = np.asarray(mesh.positions, dtype=np.float64)
    lo, hi = measured.bounds
    centre = 0.5 * (lo + hi)
    keep, point_of, repeated = welded(mesh)
    points = np.empty((len(keep), 3), dtype=np.float32)
    kept = np.take(positions, keep, axis=0)  # np.take: several times faster than fancy indexing here
    for j in range(3):  # column by column: one rounding to float32, no (P, 3) float64 temporary
        np.subtract(kept[:, j], centre[j], out=points[:, j], casting="same_kind")
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int32)
    weld = np.take(point_of, faces)

    usd_mesh = UsdGeom.Mesh.Define(stage, prim_path)
    usd_mesh.AddTranslateOp(precision=UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*centre.tolist()))
    usd_mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    usd_mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    usd_mesh.CreateDoubleSidedAttr(bool(mesh.double_sided))
    usd_mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    usd_mesh.CreateFaceVertexCountsAttr(Vt.IntArray(len(faces), 3))
    usd_mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(weld.ravel()))
    # The points' own float32 bounds: rounding is monotone, so the extremes of the rounded
    # offsets are the rounded offsets of the extremes.
    extent = (np.stack([lo, hi]) - centre).astype(np.float32)
    usd_mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(extent))

    primvars = UsdGeom.PrimvarsAPI(usd_mesh.GetPrim())
    normals = np.asarray(mesh.normals, dtype=np.float64)
    length = measured.normal_lengths
    if np.abs(length - 1.0).max() <= UNIT_ENOUGH:  # the meshers' normals: rounding them is all there is to do
        unit = normals.astype(np.float32)
    else:
        unit = np.empty(normals.shape, dtype=np.float32)
        for j in range(3):
            np.divide(normals[:, j], length, out=unit[:, j], casting="same_kind")
    first_of = np.asarray(mesh.weld if mesh.weld is not None else keep[point_of])[repeated]
    _primvar(pxr, primvars, "normals", Sdf.ValueTypeNames.Normal3fArray, Vt.Vec3fArray, unit, keep,
             repeated, first_of, faces)
    _primvar(pxr, primvars, "st", Sdf.ValueTypeNames.TexCoord2fArray, Vt.Vec2fArray,
             np.asarray(mesh.uvs, dtype=np.float32), keep, repeated, first_of, faces)
    if mesh.colors is not None:
        colors = np.clip(np.asarray(mesh.colors, dtype=np.float64), 0.0, 1.0).astype(np.float32)
        _primvar(pxr, primvars, "displayColor", Sdf.ValueTypeNames.Color3fArray, Vt.Vec3fArray, colors, keep,
                 repeated, first_of, faces)
    for name in sorted(mesh.attributes or {}):
        if name in RESERVED_PRIMVARS:
            raise ExportError(f"cannot export to USD: surface {mesh.name!r}: an attribute cannot be named "
                              f"{name!r}, the name of USD's own primvar")
        _primvar(pxr, primvars, name, Sdf.ValueTypeNames.FloatArray, Vt.FloatArray,
                 np.asarray(mesh.attributes[name], dtype=np.float32), keep, repeated, first_of, faces)
    return usd_mesh


def _primvar(pxr, primvars, name, value_type, array_type, values, keep, repeated, first_of, faces) -> None:
    """"vertex" when every repeated vertex has the value of the vertex it repeats, else indexed
    "faceVarying" (values per vertex, indices per triangle corner)."""
    UsdGeom, Vt = pxr.UsdGeom, pxr.Vt
    if np.array_equal(values[repeated], values[first_of]):
        primvar = primvars.CreatePrimvar(name, value_type, UsdGeom.Tokens.vertex)
        primvar.Set(array_type.FromNumpy(np.take(values, keep, axis=0)))
        return
    primvar = primvars.CreatePrimvar(name, value_type, UsdGeom.Tokens.faceVarying)
    primvar.Set(array_type.FromNumpy(np.ascontiguousarray(values)))
    primvar.SetIndices(Vt.IntArray.FromNumpy(faces.ravel()))


def _define_material(pxr: _Pxr, stage, prim_path, material: Material, vertex_colors: bool = False):
    """A UsdPreviewSurface material. ``vertex_colors``: its diffuseColor reads the mesh's
    ``displayColor`` primvar through a UsdPrimvarReader_float3 (the material's colour as the
    fallback), since renderers shade a mesh with its bound material and would otherwise not
    show the vertex colours. The ARKit rules allow only the float2 primvar reader, so a .usdz
    keeps the plain material colour (its meshes still carry displayColor)."""
    Gf, Sdf, UsdShade = pxr.Gf, pxr.Sdf, pxr.UsdShade
    usd_material = UsdShade.Material.Define(stage, prim_path)
    shader = UsdShade.Shader.Define(stage, prim_path.AppendChild("PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    diffuse = shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    color = Gf.Vec3f(*map(float, material.color))
    diffuse.Set(color)
    if vertex_colors:
        reader = UsdShade.Shader.Define(stage, prim_path.AppendChild("DisplayColor"))
        reader.CreateIdAttr("UsdPrimvarReader_float3")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("displayColor")
        reader.CreateInput("fallback", Sdf.ValueTypeNames.Float3).Set(color)
        diffuse.ConnectToSource(reader.ConnectableAPI(), "result", UsdShade.AttributeType.Output,
                                Sdf.ValueTypeNames.Float3)
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(float(material.roughness))
    shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(float(material.metallic))
    usd_material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return usd_material
