"""Atomic writes: the target holds the old bytes or the complete new ones, never anything else."""

from __future__ import annotations

import os
import stat

import pytest

from cgamesh.errors import ExportError
from cgamesh.export import atomic
from cgamesh.export.atomic import atomic_write


def test_writes_a_new_file(tmp_path):
    with atomic_write(tmp_path / "a.bin") as f:
        f.write(b"hello")
    assert (tmp_path / "a.bin").read_bytes() == b"hello"
    assert os.listdir(tmp_path) == ["a.bin"]


def test_replaces_an_existing_file(tmp_path):
    (tmp_path / "a.bin").write_bytes(b"old")
    with atomic_write(str(tmp_path / "a.bin")) as f:
        f.write(b"new")
    assert (tmp_path / "a.bin").read_bytes() == b"new"
    assert os.listdir(tmp_path) == ["a.bin"]


def test_target_untouched_until_the_block_ends(tmp_path):
    (tmp_path / "a.bin").write_bytes(b"old")
    with atomic_write(tmp_path / "a.bin") as f:
        f.write(b"new")
        f.flush()
        assert (tmp_path / "a.bin").read_bytes() == b"old"
        (tmp_name,) = set(os.listdir(tmp_path)) - {"a.bin"}
        assert tmp_name.startswith(".a.bin.")  # hidden, beside the target


def test_exception_in_block_propagates_unchanged_and_cleans_up(tmp_path):
    (tmp_path / "a.bin").write_bytes(b"old")
    with pytest.raises(KeyError):
        with atomic_write(tmp_path / "a.bin") as f:
            f.write(b"partial")
            raise KeyError("boom")
    assert (tmp_path / "a.bin").read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["a.bin"]


@pytest.mark.parametrize("stage", ["fsync", "replace"])
def test_os_failure_after_temp_file_is_an_export_error(tmp_path, monkeypatch, stage):
    (tmp_path / "a.bin").write_bytes(b"old")

    def fail(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, stage, fail)
    with pytest.raises(ExportError, match=r"a\.bin: No space left on device$"):
        with atomic_write(tmp_path / "a.bin") as f:
            f.write(b"new")
    monkeypatch.undo()
    assert (tmp_path / "a.bin").read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["a.bin"]


def test_missing_directory(tmp_path):
    target = tmp_path / "missing" / "a.bin"
    with pytest.raises(ExportError) as info:
        with atomic_write(target) as f:
            f.write(b"x")
    assert str(info.value) == f"cannot write {target}: directory {target.parent} does not exist"


def test_parent_is_a_file(tmp_path):
    # Permission bits do not stop root (CI runs as root), so a file as parent stands in for an
    # unwritable directory: both fail when the temporary file is created.
    (tmp_path / "plain").write_bytes(b"")
    target = tmp_path / "plain" / "a.bin"
    with pytest.raises(ExportError, match=f"^cannot write {target}: Not a directory$"):
        with atomic_write(target) as f:
            f.write(b"x")


def test_target_is_a_directory(tmp_path):
    (tmp_path / "out.glb").mkdir()
    with pytest.raises(ExportError, match="out.glb: Is a directory$"):
        with atomic_write(tmp_path / "out.glb") as f:
            f.write(b"x")
    assert os.listdir(tmp_path) == ["out.glb"] and (tmp_path / "out.glb").is_dir()


@pytest.mark.skipif(os.name != "posix", reason="POSIX permission bits")
def test_new_file_permissions_follow_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        with atomic_write(tmp_path / "a.bin") as f:
            f.write(b"x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == 0o644
