"""The input table (cgamesh.inputs.formats): a format registered through it alone is read by the
command line, the Python API and batch.

The format is polyline_format's text polylines (``.polyl``). In this process it is registered
with ``register`` (the ``polylines`` fixture); a child process (the command line, ``cgamesh
batch``) gets it from a plugin module named in CGAMESH_PLUGINS. Every mesh is checked against
the polylines it came from: each vertex on a tube of the given radius around a segment, the
tubes reaching both ends, open at the ends or, with --caps, closed by flat discs there.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cgamesh
from cgamesh import options
from cgamesh.errors import InvalidInputError
from cgamesh.inputs import formats
from cgamesh.readers.readback import read_gltf
from polyline_format import NAME, PLUGIN_SOURCE, SUFFIXES, UNITS, probe, read_polylines, write_polylines

TESTS = Path(__file__).resolve().parent
RADIUS = 0.5  # mm, the format's unit
# Straight polylines (collinear points), so the tube's axis is the polyline itself and every
# ring vertex lies exactly RADIUS from it; in different directions, of 2 and 3 points.
POLYLINES = [
    np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 4.0], [0.0, 0.0, 10.0]]),
    np.array([[5.0, 0.0, 0.0], [5.0, 4.0, 3.0], [5.0, 8.0, 6.0]]),
    np.array([[-3.0, 2.0, 1.0], [1.0, 2.0, 1.0]]),
]
CLOSE = 2e-4  # mm: float32 positions of a mesh 10 mm across, stored relative to its centre


@pytest.fixture
def polylines():
    """The format registered in this process, and taken out again afterwards."""
    added = formats.register(NAME, SUFFIXES, read_polylines, units=UNITS, probe=probe)
    yield added
    formats.unregister(added)


@pytest.fixture
def source(tmp_path) -> Path:
    folder = tmp_path / "data"
    folder.mkdir()
    path = folder / "lines.polyl"
    write_polylines(path, POLYLINES)
    return path


def plugin_environment(tmp_path) -> dict:
    """The environment of a child process that registers the format through CGAMESH_PLUGINS."""
    plugins = tmp_path / "plugins"
    plugins.mkdir(exist_ok=True)
    (plugins / "polyl_plugin.py").write_text(PLUGIN_SOURCE)
    path = os.pathsep.join([str(plugins), str(TESTS), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, formats.PLUGINS_VARIABLE: "polyl_plugin", "PYTHONPATH": path, "OPENBLAS_NUM_THREADS": "1"}


def cgamesh_command(tmp_path, *arguments) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cgamesh_cli.main", *map(str, arguments)], capture_output=True,
                          text=True, env=plugin_environment(tmp_path), timeout=300)


def source_frame(mesh, meters_per_unit: float) -> np.ndarray:
    """A GLB mesh's world positions (glTF: +Y up, metres) back in the file's z-up frame and unit:
    glTF (x, y, z) is the file's (x, z, -y)."""
    world = mesh.positions / meters_per_unit
    return np.column_stack([world[:, 0], -world[:, 2], world[:, 1]])


def nearest_segment(points: np.ndarray):
    """For each point (P, 3): its distance to the nearest segment of POLYLINES, the index of that
    polyline and the arc length along it of the nearest point."""
    best = np.full(len(points), np.inf)
    which = np.zeros(len(points), dtype=int)
    along = np.zeros(len(points))
    for index, line in enumerate(POLYLINES):
        start_length = 0.0
        for a, b in zip(line[:-1], line[1:]):
            step = b - a
            length = np.linalg.norm(step)
            t = np.clip((points - a) @ step / length**2, 0.0, 1.0)
            distance = np.linalg.norm(points - (a + t[:, None] * step), axis=1)
            closer = distance < best
            best[closer], which[closer], along[closer] = distance[closer], index, start_length + t[closer] * length
            start_length += length
    return best, which, along


def boundary_vertices(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Indices of the vertices on an edge of one triangle only, after welding vertices at one
    position (the mesher repeats them at a seam)."""
    _, weld = np.unique(np.round(positions / CLOSE).astype(np.int64), axis=0, return_inverse=True)
    welded = weld.reshape(-1)[faces]
    edges = np.sort(welded[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = np.unique(unique[counts == 1])
    return np.flatnonzero(np.isin(weld.reshape(-1), boundary))


def assert_tubes(positions: np.ndarray, faces: np.ndarray, caps: bool) -> None:
    """The mesh is a tube of RADIUS around every polyline, reaching both of its ends, open there
    or (``caps``) closed by flat discs there."""
    distance, which, along = nearest_segment(positions)
    lengths = [np.linalg.norm(np.diff(line, axis=0), axis=1).sum() for line in POLYLINES]
    at_end = (along < CLOSE) | (along > np.take(lengths, which) - CLOSE)
    for index, length in enumerate(lengths):  # every tube runs the whole polyline
        mine = along[which == index]
        assert mine.size and mine.min() < CLOSE and mine.max() > length - CLOSE, index
    on_tube = np.abs(distance - RADIUS) < CLOSE
    boundary = boundary_vertices(positions, faces)
    if caps:
        assert boundary.size == 0  # closed
        inside = ~on_tube
        assert inside.any() and np.all(distance[inside] < RADIUS) and np.all(at_end[inside])
    else:
        assert np.all(on_tube), np.abs(distance - RADIUS).max()
        assert boundary.size and np.all(at_end[boundary])  # open, at the ends only


def test_the_format_is_in_the_table_with_its_reader_unit_and_options(polylines):
    found = formats.format_of("some/where/LINES.POLYL")  # suffixes are case-insensitive
    assert found is polylines and found.kind is formats.InputKind.CENTERLINES and found.units == UNITS
    assert ".polyl" in formats.suffixes(formats.InputKind.CENTERLINES)
    assert "radius" in options.keywords(found.kind) and "along" not in options.keywords(found.kind)


def test_the_api_meshes_a_registered_format(polylines, source):
    meshes = cgamesh.load(source, radius=RADIUS)
    assert meshes.units == UNITS and meshes.meters_per_unit == 1e-3
    assert_tubes(meshes.positions, meshes.faces, caps=False)
    capped = cgamesh.load(source, radius=RADIUS, caps=True)
    assert_tubes(capped.positions, capped.faces, caps=True)


def test_a_probe_names_the_format_of_a_file_whose_suffix_names_none(polylines, tmp_path):
    path = tmp_path / "lines.txt"
    write_polylines(path, POLYLINES, header=True)
    assert formats.find(path) is polylines
    meshes = cgamesh.load(path, radius=RADIUS)
    assert_tubes(meshes.positions, meshes.faces, caps=False)
    other = tmp_path / "other.txt"
    other.write_text("1 2 3 4 5 6\n")  # no header: no format
    with pytest.raises(InvalidInputError, match=r"other.txt: unknown input format '.txt'; expected a scene file "
                                                r"\(.yaml, .yml\) or one of .swc, .trk, .tck, .trx, .npz, .polyl"):
        cgamesh.load(other, radius=RADIUS)


@pytest.mark.parametrize("caps", [False, True])
def test_the_command_line_meshes_a_format_from_a_plugin_module(tmp_path, source, caps):
    output = tmp_path / "lines.glb"
    result = cgamesh_command(tmp_path, source, "-o", output, "--radius", RADIUS, "-q", *(["--caps"] if caps else []))
    assert (result.returncode, result.stderr) == (0, "")
    (mesh,) = read_gltf(output, world=True)
    assert_tubes(source_frame(mesh, 1e-3), mesh.faces, caps=caps)


def test_batch_meshes_a_registered_format(polylines, source, tmp_path):
    out = tmp_path / "out"
    summary = cgamesh.batch([source.parent], out, workers=1, radius=RADIUS, caps=True)  # the folder is searched
    assert (summary.done, summary.failed) == (1, 0)
    (mesh,) = read_gltf(out / "lines.glb", world=True)
    assert_tubes(source_frame(mesh, 1e-3), mesh.faces, caps=True)


@pytest.mark.parametrize("caps", [False, True])
def test_the_batch_command_meshes_a_format_from_a_plugin_module(tmp_path, source, caps):
    out = tmp_path / "out"
    result = cgamesh_command(tmp_path, "batch", source.parent, "-o", out, "--radius", RADIUS, "--workers", 1, "-q",
                             *(["--caps"] if caps else []))
    assert (result.returncode, result.stderr) == (0, "")
    (mesh,) = read_gltf(out / "lines.glb", world=True)
    assert_tubes(source_frame(mesh, 1e-3), mesh.faces, caps=caps)


def test_a_missing_plugin_module_is_one_line_and_exit_2(tmp_path, source):
    environment = {**plugin_environment(tmp_path), formats.PLUGINS_VARIABLE: "no_such_plugin_module"}
    result = subprocess.run([sys.executable, "-m", "cgamesh_cli.main", str(source), "-o", str(tmp_path / "x.glb")],
                            capture_output=True, text=True, env=environment, timeout=300)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "cgamesh: error: CGAMESH_PLUGINS: cannot import the plugin module 'no_such_plugin_module': "
        "No module named 'no_such_plugin_module'"]


def test_a_suffix_has_one_owner(polylines):
    with pytest.raises(InvalidInputError, match=r"the suffix .polyl is already the text polylines's"):
        formats.register("other polylines", [".polyl"], read_polylines)
    with pytest.raises(InvalidInputError, match=r"the suffix .swc is already the SWC neuron skeleton's"):
        formats.register("other neurons", [".swc"], read_polylines)


@pytest.mark.parametrize(("arguments", "message"), [
    ({"suffixes": ["polyl"]}, r"expected suffixes such as '.swc' \(lower case, with the dot\), got \['polyl'\]"),
    ({"suffixes": [".POLYL"]}, r"expected suffixes such as '.swc'"),
    ({"units": "furlong"}, r"units must be one of nm, um, mm, cm, m, got 'furlong'"),
    ({"reader": "no colon"}, r"expected a reader function or 'module:function', got 'no colon'"),
    ({"kind": "centerlines"}, r"expected kind InputKind.SCENE or InputKind.CENTERLINES, got 'centerlines'"),
])
def test_a_bad_registration_is_refused_naming_what_was_expected(arguments, message):
    given = {"suffixes": [".other"], "reader": read_polylines, **arguments}
    with pytest.raises(InvalidInputError, match=message):
        formats.register("bad", given.pop("suffixes"), given.pop("reader"), **given)
    assert ".other" not in formats.suffixes()


def test_the_built_in_formats_read_through_the_table_and_keep_their_units(tmp_path):
    assert formats.suffixes(formats.InputKind.SCENE) == (".yaml", ".yml")
    assert formats.suffixes(formats.InputKind.CENTERLINES)[:5] == (".swc", ".trk", ".tck", ".trx", ".npz")
    assert {f.suffixes[0]: f.units for f in formats.BUILT_IN if f.units} == {
        ".swc": "um", ".trk": "mm", ".tck": "mm", ".trx": "mm", ".npz": "m"}
    path = tmp_path / "two.npz"
    np.savez(path, points=np.concatenate(POLYLINES), offsets=np.cumsum([0] + [len(p) for p in POLYLINES]))
    lines = formats.read_centerlines(path)
    assert lines.units == "m" and formats.read_centerlines(path, units="mm").units == "mm"
    with pytest.raises(InvalidInputError, match="holds no centrelines"):
        formats.read_centerlines(TESTS.parent / "examples" / "kb_tube.yaml")
