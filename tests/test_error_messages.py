"""Regression tests for inputs that once crashed, printed warnings or gave errors without a place.

Every run here goes through the CLI in-process with numpy's warnings turned into errors: a user
mistake gives exactly one stderr line ``cgamesh: error: ...`` and exit status 2 (naming the
file and line, or the flag), and a valid input gives finite geometry.
"""

from __future__ import annotations

import contextlib
import io
import re
import warnings

import numpy as np
import pytest

from cgamesh_cli.main import main
from cgamesh.errors import ExportError
from cgamesh.export.options import WriteOptions
from cgamesh.material import Material
from cgamesh.meshing.mesh import SurfaceMesh
from cgamesh.readers.readback import read_gltf

RING = "{center: [0, 0, 0], normal: [0, 0, 1], radius: 1}"
SMALLER = "{center: [0, 0, 2], normal: [0, 0, 1], radius: 0.5}"
THIRD = "{center: [0, 1, 3], normal: [0, 1, 1], radius: 0.5}"


def scene(controls, curve="linear", extra="", tail=""):
    body = "".join(f"      - {c}\n" for c in controls)
    return (f"cgamesh: 1\nsurfaces:\n  - name: tube\n    type: circles\n    curve: {curve}\n{extra}"
            f"    controls:\n{body}{tail}")


def run(argv):
    """(exit status, stdout, stderr) of the CLI with every warning an error."""
    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def refused(argv, pattern: str) -> str:
    """Run; assert exit 2 and one stderr line matching ``pattern``; return the line."""
    status, _, err = run(argv)
    assert status == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("cgamesh: error: "), err
    assert re.search(pattern, lines[0]), lines[0]
    return lines[0]


def meshed(tmp_path, text, *flags, name="out.glb"):
    """Write the scene, mesh it to a GLB, return its meshes read back (in the file's frame)."""
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    out = tmp_path / name
    status, stdout, err = run([path, "-o", out, *(flags or ("--around", "12", "--along", "24"))])
    assert status == 0 and err == "", err
    return read_gltf(out, world=True)


def assert_finite_unit(meshes):
    for mesh in meshes:
        assert np.all(np.isfinite(mesh.positions)) and np.all(np.isfinite(mesh.uvs))
        np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)


def degenerate_triangles(mesh) -> int:
    """Triangles of area <= 1e-12 of their longest edge squared (check's measure), in float32."""
    p = mesh.positions.astype(np.float32).astype(np.float64)[mesh.faces]
    area2 = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    longest = np.max([np.sum((p[:, i] - p[:, j]) ** 2, axis=1) for i, j in ((0, 1), (1, 2), (2, 0))], axis=0)
    return int(np.count_nonzero(0.5 * area2 <= 1e-12 * longest))


# --- geometry that once failed -------------------------------------------------------------------

def test_identical_consecutive_controls_of_a_linear_tube_mesh(tmp_path):
    meshes = meshed(tmp_path, scene([RING, SMALLER, SMALLER, THIRD]))
    assert_finite_unit(meshes)
    assert degenerate_triangles(meshes[0]) == 0


@pytest.mark.parametrize("curve", ["linear", "bezier", "kb", "catmull_rom"])
def test_controls_all_the_same_are_refused_with_their_line(tmp_path, curve):
    path = tmp_path / "same.yaml"
    path.write_text(scene([RING, RING, RING], curve=curve))
    refused([path, "-o", tmp_path / "x.glb"], r"same\.yaml:3: surfaces\[0\]\.controls: every control is the same circle")
    assert not (tmp_path / "x.glb").exists()


def test_nearly_identical_consecutive_controls_give_no_degenerate_triangles(tmp_path):
    near = "{center: [0, 0, 1.0e-9], normal: [0, 0, 1], radius: 1}"
    meshes = meshed(tmp_path, scene([RING, near, THIRD]), "--around", "16", "--along", "32")
    assert_finite_unit(meshes)
    assert degenerate_triangles(meshes[0]) == 0


@pytest.mark.parametrize("sine", [1e-6, 1e-9, 1e-11])
def test_nearly_collinear_through_points_give_their_circle(tmp_path, sine):
    """The circle through three nearly collinear points (radius up to 1e11 of their spread)."""
    points = lambda z: f"[[0, 0, {z}], [1, 0, {z}], [2, {sine}, {z}]]"  # noqa: E731
    # The second circle as large, one radius higher: a surface of the circles' own size.
    meshes = meshed(tmp_path, scene([f"{{through: {points(0)}}}", f"{{through: {points(1.0 / sine)}}}"]))
    assert_finite_unit(meshes)
    # Circumcentre of (0, 0), (1, 0), (2, s): on x = 0.5, equidistant from (0, 0) and (2, s).
    centre_y = (2.0 + sine**2) / (2.0 * sine)
    radius = np.hypot(0.5, centre_y)
    ring = read_first_ring(meshes[0], 12)
    np.testing.assert_allclose(np.hypot(ring[:, 0] - 0.5, ring[:, 1] - centre_y) / radius, 1.0, atol=1e-6)
    np.testing.assert_allclose(ring[:, 2] / radius, 0.0, atol=1e-6)


def read_first_ring(mesh, around):
    """The first ring's vertices in the scene file's axes (glTF's +Y up mapped back to z up)."""
    x, y, z = mesh.positions[: around + 1].astype(np.float64).T
    return np.stack([x, -z, y], axis=1)


@pytest.mark.parametrize("normal", ["[0, 0, 1.0e-200]", "[0, 0, 5.0e-324]", "[1.0e300, 0, 0]", "[0, -1.0e-310, 0]"])
def test_any_finite_non_zero_normal_is_a_direction(tmp_path, normal):
    meshes = meshed(tmp_path, scene([f"{{center: [0, 0, 0], normal: {normal}, radius: 1}}", SMALLER]))
    assert_finite_unit(meshes)
    ring = read_first_ring(meshes[0], 12)
    np.testing.assert_allclose(np.linalg.norm(ring, axis=1), 1.0, atol=1e-6)


@pytest.mark.parametrize("radius", ["1.0e-300", "1.0e29"])
def test_tubes_of_extreme_size(tmp_path, radius):
    r = float(radius)
    controls = [f"{{center: [0, 0, 0], normal: [0, 0, 1], radius: {radius}}}",
                f"{{center: [0, 0, {2 * r!r}], normal: [0, 1, 1], radius: {radius}}}"]
    meshes = meshed(tmp_path, scene(controls))
    assert_finite_unit(meshes)


def test_rational_weights_scale_freely_and_their_ratio_is_bounded(tmp_path):
    heavy = lambda c, w: c.replace("}", f", weight: {w}}}")  # noqa: E731
    assert_finite_unit(meshed(tmp_path, scene([heavy(RING, "1e300"), heavy(SMALLER, "1e300")], "rational_bezier")))
    path = tmp_path / "w.yaml"
    path.write_text(scene([heavy(RING, "1e-300"), SMALLER], "rational_bezier"))
    refused([path, "-o", tmp_path / "w.glb"], r"w\.yaml:7: surfaces\[0\]\.controls\[0\]\.weight must be at least 1e-12")


def test_a_tiny_uv_scale_is_refused_before_anything_is_written(tmp_path):
    path = tmp_path / "uv.yaml"
    path.write_text(scene([RING, SMALLER], extra="    uv_scale: 1.0e-300\n"))
    for name in ("a.glb", "a.usda", "a.ply"):
        refused([path, "-o", tmp_path / name], r"uv\.yaml:3: surfaces\[0\]\.uv_scale must be at least [0-9.e+-]+ .* got 1e-300")
        assert not (tmp_path / name).exists()


def test_the_smallest_uv_scale_accepted_writes_finite_float32(tmp_path):
    path = tmp_path / "uv.yaml"
    path.write_text(scene([RING, SMALLER], extra="    uv_scale: 1.0e-300\n"))
    line = refused([path, "-o", tmp_path / "a.glb"], "at least")
    least = float(re.search(r"at least ([0-9.e+-]+)", line).group(1)) * 1.001
    meshes = meshed(tmp_path, scene([RING, SMALLER], extra=f"    uv_scale: {least!r}\n"))
    assert np.all(np.isfinite(meshes[0].uvs.astype(np.float32)))


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".usda", ".ply", ".stl", ".obj"])
def test_no_writer_writes_a_non_finite_or_float32_overflowing_value(tmp_path, suffix):
    """The final guard: whatever reaches a writer, NaN, infinity or > float32 max is refused."""
    from cgamesh.export.registry import write

    if suffix == ".usda":
        pytest.importorskip("pxr")
    base = dict(name="s", positions=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]),
                normals=np.tile([0.0, 0, 1], (3, 1)), uvs=np.zeros((3, 2)), faces=np.array([[0, 1, 2]]))
    bad = {"positions": np.array([[0.0, 0, 0], [1e39, 0, 0], [0, 1, 0]]),
           "uvs": np.array([[0.0, 0], [np.inf, 0], [0, 1]])}
    for key, value in bad.items():
        if suffix == ".stl" and key == "uvs":
            continue  # STL stores no UVs
        mesh = SurfaceMesh(**{**base, key: value})
        out = tmp_path / f"bad_{key}{suffix}"
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ExportError, match=key):
                write(out, [(mesh, Material())], WriteOptions("z", 1.0, "m"))
        assert not out.exists()


def test_meshing_ignores_rendering_keys_and_render_reports_them(tmp_path):
    path = tmp_path / "r.yaml"
    path.write_text(scene([RING, SMALLER], tail="objects:\n  - {type: sphere, center: [0, 0, 0], radius: 0}\n"))
    assert run([path, "-o", tmp_path / "r.glb", "--around", "8", "--along", "4"])[0] == 0
    refused(["render", path, "-o", tmp_path / "r.png", "--size", "8x6"], r"r\.yaml:10: objects\[0\]\.radius must be > 0")


# --- messages ------------------------------------------------------------------------------------

def test_around_below_three_names_the_flag(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(scene([RING, SMALLER]))
    refused([path, "-o", tmp_path / "a.glb", "--around", "2"], r"^cgamesh: error: --around must be at least 3")


@pytest.mark.parametrize("argv", [["x.yaml", "-o", "x.glb", "--bogus"], ["x.yaml"], ["render", "x.yaml"],
                                  ["x.yaml", "-o", "x.glb", "--along", "many"], ["check"]])
def test_a_bad_command_line_is_one_line(argv):
    refused(argv, r"\(see cgamesh( render| check)? --help\)$")


def test_version():
    status, out, err = run(["--version"])
    assert status == 0 and err == "" and re.fullmatch(r"cgamesh \S+\n", out)


def test_non_utf8_input_names_its_line(tmp_path):
    path = tmp_path / "latin.yaml"
    path.write_bytes(scene([RING, SMALLER]).replace("name: tube", "name: tube # caf\xe9").encode("latin-1"))
    refused([path, "-o", tmp_path / "x.glb"], r"latin\.yaml:3: the scene file must be UTF-8 text, got byte 0xe9")


def test_deep_nesting_names_its_line(tmp_path):
    path = tmp_path / "deep.yaml"
    path.write_text("cgamesh: 1\nsurfaces:\n  - " + "[" * 5000 + "]" * 5000 + "\n")
    refused([path, "-o", tmp_path / "x.glb"], r"deep\.yaml:3: invalid YAML: nested too deeply")


def test_tabs_between_tokens_are_yaml_1_2(tmp_path):
    controls = [RING.replace(", ", ",\t"), "{center:\t[0,\t0, 2],\tnormal: [0, 0, 1], radius: 0.5}"]
    assert_finite_unit(meshed(tmp_path, scene(controls)))
    path = tmp_path / "indent.yaml"
    path.write_text(scene([RING, SMALLER]).replace("  - name", "\t- name"))
    refused([path, "-o", tmp_path / "x.glb"], r"indent\.yaml:3: invalid YAML")


def test_a_ribbon_through_an_end_point_at_infinity_is_refused(tmp_path):
    """Two parallel, translated segments, linearly interpolated: the pair halfway has an end at infinity."""
    path = tmp_path / "flat.yaml"
    path.write_text("cgamesh: 1\nsurfaces:\n  - name: s\n    type: point_pairs\n    curve: linear\n    controls:\n"
                    "      - {a: [0.0, 0.0, 0.0], b: [1.0, 0.0, 0.0]}\n"
                    "      - {a: [1.3416407864998738, 0.0, 0.6708203932499369], b: [2.341640786499874, 0.0, 0.6708203932499369]}\n")
    refused([path, "-o", tmp_path / "x.glb", "--around", "2", "--along", "3"],
            r"flat\.yaml:3: surfaces\[0\]: .*end point at infinity \(a flat point\) between segment 0, "
            r"alpha = 0\.49\d* and alpha = 0\.5 \(closest at alpha = 0\.5, length unbounded\); add a control in between$")


def test_ribbons_of_two_rulings(tmp_path):
    """Two rulings only (along = 2): the fold scan once indexed a third."""
    text = ("cgamesh: 1\nsurfaces:\n  - name: s\n    type: point_pairs\n    curve: linear\n    controls:\n"
            "      - {a: [0.0, 0.0, 0.0], b: [1.0, 0.0, 0.0]}\n"
            "      - {a: [1.3416407864998738, 0.0, 0.6708203932499369], b: [0.34164078649987384, 0.0, 0.6708203932499369]}\n")
    assert_finite_unit(meshed(tmp_path, text, "--around", "2", "--along", "2"))


def test_repeated_point_pairs(tmp_path):
    """A linear ribbon with a repeated control meshes; one whose controls are all the same is refused."""
    first, second = "{a: [0, 0, 0], b: [1, 0, 0]}", "{a: [0, 1, 0.5], b: [1, 1.2, 0]}"
    head = "cgamesh: 1\nsurfaces:\n  - name: s\n    type: point_pairs\n    curve: linear\n    controls:\n"
    meshes = meshed(tmp_path, head + "".join(f"      - {c}\n" for c in (first, second, second)),
                    "--around", "3", "--along", "9")
    assert_finite_unit(meshes)
    assert degenerate_triangles(meshes[0]) == 0
    path = tmp_path / "same.yaml"
    path.write_text(head + f"      - {first}\n" * 2)
    refused([path, "-o", tmp_path / "x.glb"], r"same\.yaml:3: .*every control is the same point pair")


def test_a_real_process_under_python_w_error(tmp_path):
    """The command as a process with every warning an error: the -z tube meshes, a bad flag is one line."""
    import subprocess
    import sys

    path = tmp_path / "minus_z.yaml"
    path.write_text(scene(["{center: [0, 0, 0], normal: [0, 0, -1], radius: 1}",
                           "{center: [0, 0, 2], normal: [0, 0, -1], radius: 0.5}"]))
    command = [sys.executable, "-W", "error", "-m", "cgamesh_cli.main", str(path), "-o", str(tmp_path / "t.glb")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    done = subprocess.run(command + ["--around", "2"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "--around" in done.stderr, done.stderr


def test_nearly_identical_controls_to_a_tolerance_give_no_degenerate_triangles(tmp_path):
    near = "{center: [0, 0, 1.0e-9], normal: [0, 0, 1], radius: 1}"
    path = tmp_path / "scene.yaml"
    path.write_text(scene([RING, near, THIRD]))
    status, out, err = run([path, "-o", tmp_path / "near.glb", "--tolerance", "1e-2"])
    assert status == 0 and err == "", err
    assert float(re.search(r"max deviation ([0-9.e+-]+),", out).group(1)) <= 1e-2
    meshes = read_gltf(tmp_path / "near.glb", world=True)
    assert_finite_unit(meshes)
    assert degenerate_triangles(meshes[0]) == 0


def test_opposite_circles_unaligned_interpolating_through_a_line_are_refused_where(tmp_path):
    """Blade interpolation between circles of opposite orientation (align: false) passes through
    a line, a circle through infinity; a ring on it (alpha = 1/3 here, ring 13 of 40) is one line
    naming the surface, segment and alpha, no warning, no NaN."""
    along = 40
    path = tmp_path / "opposite.yaml"
    path.write_text(scene(["{center: [0, 0, 0], normal: [1, 0, 0], radius: 1.0}",
                           "{center: [1.3416407864998738, 0, 0.6708203932499369], normal: [-1, 0, 0], radius: 0.5}"],
                          extra=f"    align: false\n    resolution: {{around: 3, along: {along}}}\n"))
    refused([path, "-o", tmp_path / "o.glb"], r"opposite\.yaml:3: surfaces\[0\]: surface 'tube': the interpolated circle turns "
                                              r"into a line \(a circle through infinity\) between segment 0, "
                                              r"alpha = 0\.32\d* and alpha = 0\.33\d* \(closest at alpha = 0\.333333, "
                                              r"radius unbounded\); controls 0 and 1 have opposite orientations "
                                              r"\(align: false\); set align: true, or interpolation: motor$")
    assert not (tmp_path / "o.glb").exists()


@pytest.mark.parametrize("points, radius, pattern", [
    ([[0, 0, 0], [1e-310, 0, 0], [2e-310, 1e-310, 0]], "1e-3", r"point 0: expected lengths between 1e-150 and 1e\+150 .*got a step of 1e-310"),
    ([[0, 0, 0], [1e-200, 0, 0], [1, 1, 0]], "0.1", r"point 0: .*got a step of 1e-200 to the next point"),
    ([[0, 0, 0], [1e300, 0, 0], [2e300, 1e300, 0]], "1", r"point 1: .*got a coordinate of 1e\+300"),
    ([[0, 0, 0], [1, 0, 0], [2, 1, 0]], "1e-310", r"point 0: .*got a radius of 1e-310"),
    ([[0, 0, 0], [1, 0, 0], [2, 1, 0]], "1e200", r"point 0: .*got a radius of 1e\+200"),
])
def test_centrelines_beyond_float64_lengths_are_refused_where(tmp_path, points, radius, pattern):
    """Steps, coordinates and radii whose squares would underflow or overflow are one located line,
    before any arithmetic (no numpy warning: run() makes every warning an error), nothing written."""
    path = tmp_path / "lines.npz"
    np.savez(path, points=np.array(points, dtype=float), offsets=np.array([0, len(points)]))
    refused([path, "-o", tmp_path / "t.glb", "--radius", radius], pattern)
    assert not (tmp_path / "t.glb").exists()


def test_a_skeleton_node_too_close_to_its_parent_is_named_with_its_line(tmp_path):
    path = tmp_path / "tree.swc"
    path.write_text("# a neuron\n1 1 0 0 0 1 -1\n2 3 1e-200 0 0 0.5 1\n3 3 5 0 0 0.5 2\n")
    refused([path, "-o", tmp_path / "t.glb"], r"node 1 \(line 2\): .*got a step of 1e-200")
