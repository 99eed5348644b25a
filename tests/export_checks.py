"""Checks of exported files shared by the export tests: USD compliance and mesh checks, reloads."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

# glTF's +Y-up frame from each source up axis: out = points @ AXIS_MAP[up].T
AXIS_MAP = {"z": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]), "y": np.eye(3)}


def pxr_or_skip():
    """The pxr package with ComplianceChecker; a loud skip locally, a failure under CI."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            from pxr.UsdUtils import ComplianceChecker  # noqa: F401
        import pxr
    except ImportError as exc:
        reason = f"usd-core with ComplianceChecker (pinned 26.5 in the test extra) is not installed: {exc}"
        if os.environ.get("CI"):
            pytest.fail(f"CI: {reason}", pytrace=False)
        pytest.skip(f"SKIPPED, NOT CHECKED: {reason}")
    return pxr


def usd_compliance(path) -> list[str]:
    """Errors, failed rules and warnings of usd-core's ComplianceChecker (usdchecker's rules; for
    .usdz also the ARKit rules)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from pxr.UsdUtils import ComplianceChecker

        checker = ComplianceChecker(arkit=str(path).endswith(".usdz"))
        checker.CheckCompliance(str(path))
    return list(checker.GetErrors()) + list(checker.GetFailedChecks()) + list(checker.GetWarnings())


def check_usd_file(path, meshes, *, up: str, meters_per_unit: float) -> None:
    """Compliance, stage metadata, the mesh checks the checkers skip, and a reload of points,
    normals and st equal to the source meshes (compared per triangle corner)."""
    from pxr import Usd, UsdGeom, UsdShade

    from cgamesh.readers.readback import expand_usd_mesh

    problems = usd_compliance(path)
    assert problems == [], f"{path}: {problems}"
    stage = Usd.Stage.Open(str(path))
    usdz = str(path).endswith(".usdz")
    expected_up = "Y" if usdz or up == "y" else "Z"
    assert UsdGeom.GetStageUpAxis(stage) == expected_up
    assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(meters_per_unit)
    root = stage.GetDefaultPrim()
    assert root.IsValid()
    cache = UsdGeom.XformCache()
    for mesh, _ in meshes:
        prim = root.GetChild(mesh.name)
        assert prim.IsA(UsdGeom.Mesh), mesh.name
        usd_mesh = UsdGeom.Mesh(prim)
        assert usd_mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
        points = np.asarray(usd_mesh.GetPointsAttr().Get(), dtype=np.float64)
        counts = np.asarray(usd_mesh.GetFaceVertexCountsAttr().Get())
        indices = np.asarray(usd_mesh.GetFaceVertexIndicesAttr().Get())
        # topology
        assert len(counts) == mesh.triangle_count and (counts == 3).all()
        assert len(indices) == counts.sum() and indices.min() >= 0 and indices.max() < len(points)
        assert len(np.unique(indices)) == len(points), "every point is used"
        # counts per interpolation
        primvars = UsdGeom.PrimvarsAPI(prim)
        for name in ("normals", "st"):
            primvar = primvars.GetPrimvar(name)
            assert primvar, name
            values, interpolation = primvar.Get(), primvar.GetInterpolation()
            if primvar.IsIndexed():
                used = np.asarray(primvar.GetIndices())
                assert used.min() >= 0 and used.max() < len(values)
                n = len(used)
            else:
                n = len(values)
            expected = {"vertex": len(points), "faceVarying": len(indices), "uniform": len(counts),
                        "constant": 1}[interpolation]
            assert n == expected, (name, interpolation, n, expected)
        # extent
        extent = np.asarray(usd_mesh.GetExtentAttr().Get(), dtype=np.float64)
        np.testing.assert_array_equal(extent, [points.min(axis=0), points.max(axis=0)])
        # material
        bound, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        assert bound and bound.GetPrim().IsValid()
        # reload: per triangle corner, through the mesh's local-to-world transform
        corners = expand_usd_mesh(usd_mesh)
        matrix = np.array(cache.GetLocalToWorldTransform(prim), dtype=np.float64)
        world = corners["points"] @ matrix[:3, :3] + matrix[3, :3]
        expected = mesh.positions[mesh.faces].reshape(-1, 3)
        if usdz and up == "z":
            expected = expected @ AXIS_MAP["z"].T
        size = max(np.ptp(expected, axis=0).max(), 1e-12)
        np.testing.assert_allclose(world, expected, rtol=0, atol=1e-6 * size + 1e-6 * np.abs(expected).max())
        np.testing.assert_allclose(corners["normals"], mesh.normals[mesh.faces].reshape(-1, 3), atol=1e-6)
        np.testing.assert_allclose(corners["st"], mesh.uvs[mesh.faces].reshape(-1, 2), atol=1e-6)
        assert bool(usd_mesh.GetDoubleSidedAttr().Get()) is bool(mesh.double_sided)


def check_gltf_reload(path, meshes, *, up: str, meters_per_unit: float, quantized: bool, tangents: bool) -> None:
    """World positions, normals, UVs (and tangents) read back equal the meshes', within the
    precision of the stored types."""
    from cgamesh.readers.readback import read_gltf

    loaded = read_gltf(path, world=True)
    assert [m.name for m in loaded] == [m.name for m, _ in meshes]
    for got, (mesh, _) in zip(loaded, meshes):
        assert (got.vertex_count, got.triangle_count) == (mesh.vertex_count, mesh.triangle_count)
        np.testing.assert_array_equal(got.faces, mesh.faces)
        expected = mesh.positions @ AXIS_MAP[up].T * meters_per_unit
        size = np.ptp(expected, axis=0).max()
        position_tolerance = size / 32767.0 if quantized else 1e-6 * size
        np.testing.assert_allclose(got.positions, expected, rtol=0, atol=position_tolerance)
        normal_tolerance = 0.02 if quantized else 1e-6
        np.testing.assert_allclose(got.normals, mesh.normals @ AXIS_MAP[up].T, atol=normal_tolerance)
        uv_tolerance = 1.0 / 65535.0 if quantized and mesh.uvs.min() >= 0 and mesh.uvs.max() <= 1 else 1e-6
        np.testing.assert_allclose(got.uvs, mesh.uvs, atol=uv_tolerance)
        if tangents:
            from cgamesh.meshing.uv import tangents_of

            reference = tangents_of(mesh)
            np.testing.assert_allclose(got.tangents[:, :3], reference[:, :3] @ AXIS_MAP[up].T, atol=normal_tolerance)
            np.testing.assert_array_equal(got.tangents[:, 3], reference[:, 3])
        else:
            assert got.tangents is None
