"""The cgamesh command: a summary line on success; one line, exit 2 and no output on every user error."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from cgamesh_cli.main import main

VALID = """\
cgamesh: 1
surfaces:
  - name: tube
    type: circles
    curve: catmull_rom
    controls:
      - {center: [0, 0, 0], normal: [0, 0, 1], radius: 0.5}
      - {center: [0.2, 0.1, 1], normal: [0.2, 0.1, 1], radius: 0.4}
      - {center: [0.5, 0.1, 2], normal: [0.3, 0, 1], radius: 0.45}
    resolution: {around: 12, along: 20}
"""
SUMMARY = re.compile(r"^(?P<path>.+\.glb): 1 surface, (?P<vertices>\d+) vertices, (?P<triangles>\d+) triangles, "
                     r"\d+\.\d\d s, (?P<bytes>\d+) bytes$")


def _circles_scene(controls, curve="linear", extra=""):
    body = "".join(f"      - {c}\n" for c in controls)
    return f"cgamesh: 1\nsurfaces:\n  - name: tube\n    type: circles\n    curve: {curve}\n{extra}    controls:\n{body}"


RING = "{center: [0, 0, 0], normal: [0, 0, 1], radius: 1.0}"
OTHER = "{center: [0, 0, 2], normal: [0, 0, 1], radius: 1.0}"

# name -> (scene text, whether the message must carry a line number)
MALFORMED = {
    "missing_key": (VALID.replace("    type: circles\n", ""), True),
    "unknown_key": (VALID.replace("    type: circles\n", "    type: circles\n    colour: red\n"), True),
    "wrong_type": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: big}"]), True),
    "wrong_type_vector": (_circles_scene([RING, "{center: [0, 0], normal: [0, 0, 1], radius: 1.0}"]), True),
    "nan": (_circles_scene([RING, "{center: [0, .nan, 2], normal: [0, 0, 1], radius: 1.0}"]), True),
    "infinity": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: .inf}"]), True),
    "zero_radius": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: 0}"]), True),
    "negative_radius": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: -1e-3}"]), True),
    "zero_normal": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 0], radius: 1.0}"]), True),
    "one_control": (_circles_scene([RING]), True),
    "collinear_through": (_circles_scene([RING, "{through: [[0, 0, 1], [1, 1, 1], [2, 2, 1]]}"]), True),
    "zero_weight": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: 1.0, weight: 0}"],
                                   curve="rational_bezier"), True),
    "negative_weight": (_circles_scene([RING, "{center: [0, 0, 2], normal: [0, 0, 1], radius: 1.0, weight: -2}"],
                                       curve="rational_bezier"), True),
    "singular_interpolation": (_circles_scene([RING, "{center: [0, 0, 0], normal: [0, 0, -1], radius: 1.0}"],
                                              extra="    align: false\n"), True),
    "yaml_syntax": (VALID.replace("    type: circles\n", "    type: [circles\n"), True),
}
SENTINEL = b"an existing output file\x00 that a failed run must leave alone\n"


def _write(tmp_path, text, name="scene.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _cgamesh_script():
    script = Path(sys.executable).with_name("cgamesh")
    if not script.exists():
        pytest.fail(f"the cgamesh console script is not installed next to {sys.executable}", pytrace=False)
    return script


# --- success ------------------------------------------------------------------------------------

def test_valid_scene_writes_a_glb_and_prints_the_summary_line(tmp_path, capsys):
    scene, output = _write(tmp_path, VALID), tmp_path / "tube.glb"
    code = main([str(scene), "-o", str(output)])
    out, err = capsys.readouterr()
    match = SUMMARY.match(out.rstrip("\n"))
    assert (code == 0 and err == "" and out.count("\n") == 1 and match is not None
            and match["path"] == str(output) and int(match["vertices"]) == 20 * 13
            and int(match["bytes"]) == output.stat().st_size and output.read_bytes()[:4] == b"glTF")


def test_quiet_prints_nothing(tmp_path, capsys):
    scene, output = _write(tmp_path, VALID), tmp_path / "tube.glb"
    code = main([str(scene), "-o", str(output), "-q"])
    assert code == 0 and capsys.readouterr() == ("", "") and output.exists()


def test_console_script_builds_in_a_real_process(tmp_path):
    scene, output = _write(tmp_path, VALID), tmp_path / "tube.glb"
    done = subprocess.run([str(_cgamesh_script()), str(scene), "-o", str(output)],
                          capture_output=True, text=True, timeout=120)
    assert (done.returncode == 0 and done.stderr == "" and SUMMARY.match(done.stdout.rstrip("\n"))
            and output.read_bytes()[:4] == b"glTF")


def test_the_command_line_never_imports_clifford(tmp_path):
    scene, output = _write(tmp_path, VALID), tmp_path / "tube.glb"
    probe = textwrap.dedent(f"""
        import sys
        from cgamesh_cli.main import main
        after_import = sorted(m for m in sys.modules if m.split(".")[0] == "clifford")
        code = main([{str(scene)!r}, "-o", {str(output)!r}, "-q"])
        after_build = sorted(m for m in sys.modules if m.split(".")[0] == "clifford")
        print(code, after_import, after_build)
    """)
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.split() == ["0", "[]", "[]"] and output.exists(), done.stderr


# --- user errors --------------------------------------------------------------------------------

def _run_failing(tmp_path, capsys, text, existing):
    """Run a build of ``text``; return (exit code, stderr, stdout, files after, expected files)."""
    scene, output = _write(tmp_path, text, "bad_scene.yaml"), tmp_path / "out.glb"
    if existing:
        output.write_bytes(SENTINEL)
    code = main([str(scene), "-o", str(output)])
    out, err = capsys.readouterr()
    files = sorted(p.name for p in tmp_path.iterdir())
    expected = sorted(["bad_scene.yaml"] + (["out.glb"] if existing else []))
    return code, err, out, files, expected, output


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_scene_exits_2_with_one_line_naming_file_and_line(tmp_path, capsys, case):
    text, with_line = MALFORMED[case]
    code, err, out, _, _, _ = _run_failing(tmp_path, capsys, text, existing=False)
    line_pattern = r"bad_scene\.yaml:\d+:" if with_line else r"bad_scene\.yaml"
    assert (code == 2 and out == "" and err.count("\n") == 1 and err.endswith("\n")
            and re.search(line_pattern, err) and "Traceback" not in err), err


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_scene_writes_no_file(tmp_path, capsys, case):
    _, _, _, files, expected, _ = _run_failing(tmp_path, capsys, MALFORMED[case][0], existing=False)
    assert files == expected


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_scene_leaves_an_existing_output_byte_identical(tmp_path, capsys, case):
    _, _, _, files, expected, output = _run_failing(tmp_path, capsys, MALFORMED[case][0], existing=True)
    assert files == expected and output.read_bytes() == SENTINEL


def test_singular_interpolation_message_names_the_surface_and_alpha(tmp_path, capsys):
    code, err, _, _, _, _ = _run_failing(tmp_path, capsys, MALFORMED["singular_interpolation"][0], existing=False)
    assert code == 2 and "surfaces[0]" in err and "tube" in err and "alpha = 0.5" in err


def test_missing_scene_file_exits_2_with_one_line(tmp_path, capsys):
    code = main([str(tmp_path / "nowhere.yaml"), "-o", str(tmp_path / "out.glb")])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and "nowhere.yaml" in err and not (tmp_path / "out.glb").exists()


@pytest.mark.parametrize("output_name", ["out.xyz", "out", "out.glb.txt"])
def test_unknown_output_extension_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, output_name):
    scene = _write(tmp_path, VALID)
    code = main([str(scene), "-o", str(tmp_path / output_name)])
    out, err = capsys.readouterr()
    assert (code == 2 and out == "" and err.count("\n") == 1 and output_name in err and "Traceback" not in err
            and sorted(p.name for p in tmp_path.iterdir()) == ["scene.yaml"])


def test_console_script_reports_a_malformed_scene_in_one_line(tmp_path):
    scene, output = _write(tmp_path, MALFORMED["zero_radius"][0], "bad_scene.yaml"), tmp_path / "out.glb"
    done = subprocess.run([str(_cgamesh_script()), str(scene), "-o", str(output)],
                          capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONWARNINGS": ""})
    assert (done.returncode == 2 and done.stdout == "" and done.stderr.count("\n") == 1
            and re.search(r"bad_scene\.yaml:\d+:", done.stderr) and not output.exists())
