"""The table of meshing options (cgamesh.options) is the only list: the command line's flags, the
API's keywords, batch's options and the values handed to the pipelines and writers are exactly
the table's, so an option added, renamed or dropped in one place and not the others fails here.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import pytest

import cgamesh
from cgamesh import api, options
from cgamesh.batching.job import mesh_input
from cgamesh.pipelines.tube_options import TubeOptions
from cgamesh.errors import InvalidInputError
from cgamesh.export.options import GltfOptions
from cgamesh.inputs.formats import InputKind
from cgamesh.pipelines.scene import Resolution
from cgamesh_cli import batch as batch_command
from cgamesh_cli import build as build_command
from cgamesh_cli.main import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TABLE = tuple(option.name for option in options.OPTIONS)
# The flags each command has besides the table's: its own, not meshing options.
BUILD_OWN = {"help", "scene", "output", "report", "max_memory", "quiet"}
BATCH_OWN = {"help", "inputs", "outdir", "format", "listing", "workers", "scheduler", "retries", "memory_limit",
             "force", "json", "quiet"}


def flags(parser: argparse.ArgumentParser, own: set[str]) -> dict[str, tuple[str, ...]]:
    return {action.dest: tuple(action.option_strings) for action in parser._actions if action.dest not in own}


@pytest.mark.parametrize(("command", "own"), [(build_command, BUILD_OWN), (batch_command, BATCH_OWN)])
def test_each_commands_meshing_flags_are_the_tables(command, own):
    assert flags(command.build_parser(), own) == {option.name: (option.flag,) for option in options.OPTIONS}


def test_the_apis_keywords_are_the_tables_and_the_pipelines_fields():
    scene, centerlines = options.keywords(InputKind.SCENE), options.keywords(InputKind.CENTERLINES)
    assert scene == ("around", "along", "tolerance", "tangents")
    # a scene's resolution is the Resolution (tangents: the scene mesher's analytic tangents)
    assert set(scene) - {"tangents"} == {f.name for f in dataclasses.fields(Resolution)}
    # a centreline input's options are TubeOptions' fields, and the file's unit
    assert set(centerlines) == {f.name for f in dataclasses.fields(TubeOptions)} | {"units"}
    assert set(api.TUBE_KEYWORDS) == set(centerlines) - {"units"}


def test_tube_options_defaults_are_the_tables():
    for field in dataclasses.fields(TubeOptions):
        assert options.BY_NAME[field.name].default == field.default, field.name
    assert TubeOptions.from_options({}) == TubeOptions()
    assert TubeOptions.from_options({"subdivide": 0, "caps": True, "units": "mm", "along": 9, "quantize": True}) == \
        TubeOptions(subdivide=0, caps=True)


def test_the_glTF_writers_options_are_the_tables():
    assert {f.name for f in dataclasses.fields(GltfOptions)} == {o.name for o in options.OPTIONS if o.writes == "gltf"}


@pytest.mark.parametrize("name", [o for o in TABLE if o not in options.keywords(InputKind.SCENE)])
def test_a_scene_refuses_every_other_option_by_name(name):
    with pytest.raises(InvalidInputError, match=f"unknown option '{name}'; expected one of around, along, "
                                                "tolerance, tangents$"):
        cgamesh.load(EXAMPLES / "kb_tube.yaml", **{name: True})


def test_batch_takes_exactly_the_tables_options():
    options.check_batch({name: None for name in TABLE})
    with pytest.raises(InvalidInputError) as refused:
        options.check_batch({"colour_by": "radius"})
    message = str(refused.value)
    assert message.startswith("unknown meshing option colour_by; expected some of ")
    assert message.split("expected some of ")[1].split(", ") == sorted(TABLE)


@pytest.mark.parametrize(("given", "message"), [
    ({"tolerance": 0.1, "around": 8}, "--tolerance cannot be combined with --around or --along"),
    ({"tolerance": 0.1, "subdivide": 0}, "--tolerance cannot be combined with --around or --subdivide"),
    ({"watertight": True, "split": True}, "--watertight makes one surface; it cannot be combined with --split"),
    ({"keep_going": True, "strict": True}, "--keep-going and --strict exclude each other"),
    ({"subdivide": -1}, "subdivide must be >= 0, got -1"),
    ({"around": 2.5}, "around must be a whole number, got 2.5"),
    ({"caps": "yes"}, "caps must be True or False, got 'yes'"),
])
def test_batch_refuses_what_the_table_refuses(given, message):
    with pytest.raises(InvalidInputError, match=f"^{message}$"):
        options.check_batch(given)


def test_switches_off_and_unset_values_are_not_given_but_zero_is():
    assert options.given({"subdivide": 0, "split": False, "radius": None, "caps": True}) == {"subdivide": 0,
                                                                                          "caps": True}


def test_batch_keeps_subdivide_0(tmp_path):
    source = tmp_path / "line.npz"
    np.savez(source, points=np.array([[0.0, 0, 0], [0, 0, 1], [0, 0, 2]]), offsets=np.array([0, 3]))
    done = mesh_input(source, [tmp_path / "line.glb"], {"radius": 0.1, "around": 8, "subdivide": 0})
    rings = 3  # one on every node, none between: 3 rings of 8 + 1 (the seam repeated)
    assert done["vertices"] == rings * 9 == cgamesh.load(source, radius=0.1, subdivide=0).positions.shape[0]


def test_caps_from_the_command_line_close_the_tubes(tmp_path, capsys):
    source = tmp_path / "line.npz"
    np.savez(source, points=np.array([[0.0, 0, 0], [0, 0, 1], [0, 0, 2]]), offsets=np.array([0, 3]))
    for caps in ([], ["--caps"]):
        assert main([str(source), "-o", str(tmp_path / "line.glb"), "--radius", "0.1", "--subdivide", "0", "-q",
                     *caps]) == 0
        from cgamesh.readers.readback import read_gltf

        (mesh,) = read_gltf(tmp_path / "line.glb")
        expected = cgamesh.load(source, radius=0.1, subdivide=0, caps=bool(caps))
        assert mesh.vertex_count == expected.positions.shape[0]
    assert mesh.vertex_count > 3 * 9  # the caps' vertices on top of the three rings


@pytest.mark.parametrize(("argv", "message"), [
    (["--along", "4"], "--along applies to scene files; for centreline inputs give --subdivide K "
                       "(rings between consecutive nodes)"),
    (["--tolerance", "0.1", "--subdivide", "2"], "--tolerance cannot be combined with --around or --subdivide"),
    (["--split", "--watertight"], "--watertight makes one surface; it cannot be combined with --split"),
    (["--strict", "--keep-going"], "--keep-going and --strict exclude each other"),
    (["--around", "2"], "around must be >= 3, got 2"),  # the table's stricter check for tubes
    (["--subdivide", "-1"], "argument --subdivide: expected a whole number >= 0, got -1 (see cgamesh --help)"),
])
def test_the_command_line_refuses_what_the_table_refuses(tmp_path, capsys, argv, message):
    source = tmp_path / "line.npz"
    np.savez(source, points=np.array([[0.0, 0, 0], [0, 0, 1]]), offsets=np.array([0, 2]))
    assert main([str(source), "-o", str(tmp_path / "x.glb"), "--radius", "0.1", *argv]) == 2
    assert capsys.readouterr().err == f"cgamesh: error: {message}\n"
    assert not (tmp_path / "x.glb").exists()


@pytest.mark.parametrize("flag", ["--radius 1", "--caps", "--subdivide 0", "--units mm"])
def test_a_scene_file_refuses_a_centreline_flag(tmp_path, capsys, flag):
    assert main([str(EXAMPLES / "kb_tube.yaml"), "-o", str(tmp_path / "x.glb"), *flag.split()]) == 2
    assert capsys.readouterr().err == (f"cgamesh: error: {flag.split()[0]} applies to centreline inputs (.swc, .trk, "
                                       f".tck, .trx, .npz), not to the scene file {EXAMPLES / 'kb_tube.yaml'}\n")


def test_the_readme_lists_the_tables_options_and_formats():
    from cgamesh.inputs import formats

    text = (EXAMPLES.parent / "README.md").read_text()
    section = text[text.index("### Meshing options"):text.index("### Input formats")]
    rows = [line.split("|")[1:3] for line in section.splitlines() if line.startswith("| `--")]
    kinds = {frozenset({InputKind.SCENE}): "scenes", frozenset({InputKind.CENTERLINES}): "centrelines",
             options.BOTH: "both"}
    assert [(flag.strip().strip("`").split()[0], where.strip()) for flag, where in rows] == [
        (option.flag, kinds[option.inputs]) for option in options.OPTIONS]
    section = text[text.index("### Input formats"):text.index("## ", text.index("### Input formats") + 4)]
    rows = [line.split("|")[1:5] for line in section.splitlines() if line.startswith("| `.")]
    assert [(tuple(s.strip(" `") for s in suffixes.split(",")), name.strip(), kind.strip()) for suffixes, name, kind, _
            in rows] == [(f.suffixes, f.name, "scene" if f.kind is InputKind.SCENE else "centrelines")
                         for f in formats.BUILT_IN]
