"""Outputs commit all or nothing: every output and sidecar of a run, or none; interrupted and
concurrent runs never leave a temporary or a mixed pair; --report may not name an output."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cgamesh.errors import ExportError
from cgamesh.export import atomic
from cgamesh.export.atomic import all_or_nothing, atomic_files, atomic_write
from cgamesh_cli.main import main

ROOT = Path(__file__).resolve().parent.parent
KB = ROOT / "examples" / "kb_tube.yaml"
LOW = ["--around", "8", "--along", "12"]


def run(capsys, *argv) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


def listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


def test_a_failing_later_output_leaves_every_earlier_one_untouched(tmp_path, capsys):
    for name in ("a.glb", "a.gltf", "a.bin", "a.obj", "a.mtl"):
        (tmp_path / name).write_bytes(b"old " + name.encode())
    (tmp_path / "z.stl").mkdir()  # cannot be replaced by a file
    before = listing(tmp_path)
    code, err = run(capsys, KB, "-o", tmp_path / "a.glb", "-o", tmp_path / "a.gltf", "-o", tmp_path / "a.obj",
                    "-o", tmp_path / "z.stl", *LOW)
    assert code == 2 and err.count("\n") == 1 and "z.stl" in err
    assert listing(tmp_path) == before
    assert sorted(os.listdir(tmp_path)) == sorted([*before, "z.stl"])  # no temporaries


@pytest.mark.parametrize("main_file, sidecar", [("a.gltf", "a.bin"), ("a.obj", "a.mtl")])
def test_a_pair_whose_main_file_cannot_be_replaced_keeps_its_old_sidecar(tmp_path, capsys, main_file, sidecar):
    (tmp_path / main_file).mkdir()
    (tmp_path / sidecar).write_bytes(b"old")
    code, err = run(capsys, KB, "-o", tmp_path / main_file, *LOW)
    assert code == 2 and err.count("\n") == 1
    assert (tmp_path / sidecar).read_bytes() == b"old"
    assert sorted(os.listdir(tmp_path)) == sorted([main_file, sidecar])


def test_a_failed_rename_half_way_puts_the_old_files_back(tmp_path, monkeypatch):
    (tmp_path / "a").write_bytes(b"old a")
    (tmp_path / "b").write_bytes(b"old b")
    real = os.replace
    calls = []

    def failing_second(src, dst):
        calls.append(Path(dst).name)
        if Path(dst).name == "b" and str(src).endswith(".tmp"):
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", failing_second)
    with pytest.raises(ExportError, match="cannot write .*b: No space left on device"):
        with all_or_nothing():
            with atomic_write(tmp_path / "a") as f:
                f.write(b"new a")
            with atomic_write(tmp_path / "b") as f:
                f.write(b"new b")
    assert calls[:2] == ["a", "b"]  # a had been replaced when b failed
    assert listing(tmp_path) == {"a": b"old a", "b": b"old b"}


def test_an_exception_in_the_block_removes_every_staged_file(tmp_path):
    (tmp_path / "a").write_bytes(b"old")
    with pytest.raises(RuntimeError):
        with all_or_nothing():
            with atomic_files([tmp_path / "a", tmp_path / "b"]) as (fa, fb):
                fa.write(b"new")
                fb.write(b"new")
            assert len(os.listdir(tmp_path)) == 3  # a, and the two staged temporaries
            raise RuntimeError("later output failed")
    assert listing(tmp_path) == {"a": b"old"} and not atomic.LIVE_TEMPORARIES


def test_outputs_appear_only_when_all_are_written(tmp_path):
    with all_or_nothing():
        with atomic_write(tmp_path / "a") as f:
            f.write(b"a")
        assert not (tmp_path / "a").exists()
        with atomic_write(tmp_path / "b") as f:
            f.write(b"b")
    assert listing(tmp_path) == {"a": b"a", "b": b"b"}


@pytest.mark.parametrize("flags", [["--report", "{out}"], ["--report", "{dir}/./a.glb"], ["--report", "{dir}/a.bin"],
                                   ["--report", "{scene}"], ["-o", "{out}"]])
def test_report_and_outputs_may_not_name_one_file(tmp_path, capsys, flags):
    scene = tmp_path / "scene.yaml"
    scene.write_bytes(KB.read_bytes())
    out = tmp_path / "a.glb"
    out.write_bytes(b"old mesh")
    (tmp_path / "a.bin").write_bytes(b"old bin")
    extra = [f.format(out=out, dir=tmp_path, scene=scene) for f in flags]
    code, err = run(capsys, scene, "-o", out, "-o", tmp_path / "a.gltf", *extra, *LOW)
    assert code == 2 and err.count("\n") == 1 and "would overwrite" in err, err
    assert out.read_bytes() == b"old mesh" and (tmp_path / "a.bin").read_bytes() == b"old bin"
    assert scene.read_bytes() == KB.read_bytes()
    assert not (tmp_path / "a.gltf").exists()


def _env() -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


@pytest.mark.parametrize("signal_number, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_during_a_large_write_leaves_the_old_outputs_and_no_temporary(tmp_path, signal_number, status):
    """A real ``cgamesh`` process writing a GLB and a slow USD text file is stopped once the first
    temporary exists: it exits with one line, the old files stay, no temporary is left."""
    pytest.importorskip("pxr")
    old = {"big.glb": b"old glb", "big.usda": b"old usda"}
    for name, data in old.items():
        (tmp_path / name).write_bytes(data)
    process = subprocess.Popen(
        [sys.executable, "-c", "import sys; from cgamesh_cli.main import main; sys.exit(main())", str(KB),
         "-o", "big.glb", "-o", "big.usda", "--around", "512", "--along", "1024", "-q"],
        cwd=tmp_path, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not any(name.startswith(".big.") for name in os.listdir(tmp_path)):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no temporary appeared"
        time.sleep(0.002)
    process.send_signal(signal_number)
    out, err = process.communicate(timeout=120)
    assert process.returncode == status, err
    assert err.decode() == "cgamesh: interrupted\n" and out == b""
    assert listing(tmp_path) == old
    assert sorted(os.listdir(tmp_path)) == sorted(old)


WRITER = """
import os, sys, time
import cgamesh.export.atomic as atomic
from cgamesh.export.options import WriteOptions
from cgamesh.inputs.scene import load_scene
from cgamesh.pipelines.scene import Resolution, mesh_scene
from cgamesh.export.gltf import write_gltf
scene = load_scene(sys.argv[1])
meshes = mesh_scene(scene, Resolution(int(sys.argv[3]), 16))
real = os.replace
def slow_replace(src, dst):  # widen the window between the renames of the pair
    real(src, dst)
    time.sleep(0.01)
atomic.os.replace = slow_replace
for _ in range(int(sys.argv[4])):
    write_gltf(sys.argv[2], meshes, WriteOptions(scene.up, scene.meters_per_unit, scene.units))
"""


def _pair_matches(gltf: Path) -> bool:
    document = json.loads(gltf.read_text())
    (buffer,) = document["buffers"]
    return buffer["byteLength"] == (gltf.with_suffix(".bin")).stat().st_size


def test_concurrent_writers_of_one_gltf_never_leave_a_mixed_pair(tmp_path):
    """Two processes write the same .gltf over and over, with meshes of different sizes and a
    pause after each rename (so that, unserialised, their renames interleave); a reader that
    takes the same directory lock between commits always finds a matching pair."""
    import fcntl

    target = tmp_path / "shared.gltf"
    writers = [subprocess.Popen([sys.executable, "-c", WRITER, str(KB), str(target), str(around), "40"], env=_env())
               for around in (8, 24)]
    checked = 0
    while any(w.poll() is None for w in writers):
        fd = os.open(tmp_path, os.O_RDONLY)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            if target.exists():
                assert _pair_matches(target)
                checked += 1
        finally:
            os.close(fd)
        time.sleep(0.005)
    assert all(w.wait() == 0 for w in writers)
    assert _pair_matches(target)
    assert sorted(os.listdir(tmp_path)) == ["shared.bin", "shared.gltf"]
    assert checked > 0
