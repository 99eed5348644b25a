"""Several outputs from one meshing, formats by extension, lazy format libraries, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import cgamesh.pipelines.scene
from cgamesh.export import registry
from cgamesh_cli.main import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "kb_tube.yaml"
LOW = ["--around", "8", "--along", "12"]
ALL = [".glb", ".gltf", ".usda", ".usdc", ".usd", ".usdz", ".obj", ".ply", ".stl"]


def test_several_outputs_are_written_from_one_meshing(tmp_path, capsys, monkeypatch):
    pytest.importorskip("pxr")
    calls = []
    original = cgamesh.pipelines.scene.mesh_planned

    def counting(plan, *args, **kwargs):
        calls.append(plan.spec.name)
        return original(plan, *args, **kwargs)

    monkeypatch.setattr(cgamesh.pipelines.scene, "mesh_planned", counting)
    # the batched pass (cgamesh.meshing.scene_batch) meshes groups of surfaces: count them too
    from cgamesh.meshing.scene_batch import scene as batched_scene

    group = batched_scene.mesh_circle_group

    def counting_group(names, *args, **kwargs):
        calls.extend(names)
        return group(names, *args, **kwargs)

    monkeypatch.setattr(batched_scene, "mesh_circle_group", counting_group)
    outputs = [tmp_path / f"tube{suffix}" for suffix in ALL]
    assert main([str(EXAMPLE), *[a for o in outputs for a in ("-o", str(o))], *LOW]) == 0
    assert calls == ["kb_tube"]
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines] == [str(o) for o in outputs]
    for output, line in zip(outputs, lines):
        assert output.is_file() and line.endswith(" bytes")
    assert (tmp_path / "tube.bin").is_file() and (tmp_path / "tube.mtl").is_file()


@pytest.mark.parametrize("outputs", [["out.glb", "out.fbx"], ["out.usdz", "out"], ["OUT.GLB", "out.3mf"]])
def test_an_unknown_extension_among_several_exits_2_and_writes_nothing(tmp_path, capsys, outputs):
    code = main([str(EXAMPLE), *[a for o in outputs for a in ("-o", str(tmp_path / o))], *LOW])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "unknown output format" in err
    assert list(tmp_path.iterdir()) == []


def test_extensions_are_case_insensitive(tmp_path):
    assert main([str(EXAMPLE), "-o", str(tmp_path / "OUT.GLB"), *LOW, "-q"]) == 0
    assert (tmp_path / "OUT.GLB").read_bytes()[:4] == b"glTF"


@pytest.mark.parametrize("suffix", ALL)
def test_an_unwritable_path_exits_2_with_one_line(tmp_path, capsys, suffix):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    for target in (tmp_path / "missing" / f"out{suffix}", blocker / f"out{suffix}"):
        assert main([str(EXAMPLE), "-o", str(target), *LOW]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(target) in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_a_directory_as_output_is_a_one_line_error(tmp_path, capsys):
    pytest.importorskip("pxr")
    for suffix in (".glb", ".usdc", ".ply"):
        target = tmp_path / f"folder{suffix}"
        target.mkdir()
        assert main([str(EXAMPLE), "-o", str(target), *LOW]) == 2
        assert capsys.readouterr().err.count("\n") == 1
        assert target.is_dir() and list(target.iterdir()) == []
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "no temporary file is left"


def test_the_registry_is_a_plain_table():
    assert set(registry.WRITERS) == set(ALL)
    for writer in registry.WRITERS.values():
        assert writer.module.startswith("cgamesh.export.")


PROBE = """
import json, sys
from cgamesh_cli.main import main
status = main(sys.argv[1:])
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""


@pytest.mark.parametrize(("suffix", "needed", "never"), [
    (".gltf", [], ["pxr", "trimesh", "xatlas", "pymeshlab"]),
    (".usda", ["pxr"], ["trimesh", "xatlas", "pymeshlab"]),
    (".stl", ["trimesh"], ["pxr", "xatlas", "pymeshlab"]),
])
def test_a_format_library_is_imported_only_for_its_format(tmp_path, suffix, needed, never):
    if needed == ["pxr"]:
        pytest.importorskip("pxr")
    done = subprocess.run([sys.executable, "-c", PROBE, str(EXAMPLE), "-o", str(tmp_path / f"x{suffix}"), "-q", *LOW],
                          capture_output=True, text=True, timeout=120, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["status"] == 0
    roots = {name.split(".")[0] for name in result["modules"]}
    assert set(needed) <= roots and not (set(never) & roots)


def test_strict_without_report_is_refused(tmp_path, capsys):
    assert main([str(EXAMPLE), "-o", str(tmp_path / "x.glb"), "--strict", *LOW]) == 2
    assert capsys.readouterr().err.count("\n") == 1 and not (tmp_path / "x.glb").exists()
