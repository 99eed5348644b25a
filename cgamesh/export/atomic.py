"""Atomic file writes: a reader sees the old file or the complete new one, never a torn one.

The data goes to a temporary file in the target's own directory (so the final rename stays on
one file system and is atomic), is flushed and fsynced, and then replaces the target with
``os.replace``. If anything fails before that, the temporary file is removed and an existing
target is left exactly as it was.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from cgamesh.errors import ExportError


@contextmanager
def atomic_write(path: str | os.PathLike[str]) -> Iterator[BinaryIO]:
    """Open a binary file that replaces ``path`` atomically when the ``with`` block succeeds.

    Usage::

        with atomic_write("tube.glb") as f:
            f.write(data)

    An ``OSError`` (missing or unwritable directory, full disk, target is a directory...) is
    raised as :class:`ExportError` with a one-line message naming the path and the reason;
    any other exception from the block propagates unchanged. In every failure case the
    temporary file is gone and a previous file at ``path`` is untouched.
    """
    target = Path(path)
    tmp, fd = _create_temp_beside(target)
    with _replacing(tmp, target):
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            # Without fsync the rename can reach the disk before the data does, and a crash
            # would leave an empty or partial file under the final name.
            os.fsync(f.fileno())


@contextmanager
def atomic_files(paths: list[str | os.PathLike[str]]) -> Iterator[list[BinaryIO]]:
    """Like ``atomic_write`` for several files written together (a .gltf and its .bin).

    Every file is written and fsynced under a temporary name first; only when all of them are
    complete are they renamed into place, in the order given (put the file that references the
    others last). On any failure no target is touched and every temporary file is removed.
    """
    targets = [Path(p) for p in paths]
    temps: list[Path] = []
    handles: list[BinaryIO] = []
    try:
        for target in targets:
            tmp, fd = _create_temp_beside(target)
            temps.append(tmp)
            handles.append(os.fdopen(fd, "wb"))
        yield handles
        for f in handles:
            f.flush()
            os.fsync(f.fileno())
            f.close()
        for tmp, target in zip(temps, targets):
            os.replace(tmp, target)
    except BaseException as exc:
        for f in handles:
            try:
                f.close()
            except OSError:
                pass
        for tmp in temps:
            _remove_quietly(tmp)
        if isinstance(exc, OSError):
            failed = next((t for t in targets if exc.filename and Path(exc.filename).name.startswith(f".{t.name}")),
                          targets[0])
            raise ExportError(f"cannot write {failed}: {_reason(exc, failed)}") from exc
        raise
    for directory in {t.parent for t in targets}:
        _fsync_directory(directory)


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path``, with the same suffix, for libraries that write files
    themselves (pxr picks the USD format by extension). When the block succeeds the file there
    is fsynced and renamed onto ``path``; otherwise it is removed and ``path`` is untouched.
    An ``OSError`` becomes a one-line ExportError; a block that wrote nothing is one too.
    """
    target = Path(path)
    tmp, fd = _create_temp_beside(target, suffix=target.suffix)
    os.close(fd)
    with _replacing(tmp, target):
        yield tmp
        if not tmp.is_file() or tmp.stat().st_size == 0:
            raise ExportError(f"cannot write {target}: nothing was written")
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextmanager
def _replacing(tmp: Path, target: Path) -> Iterator[None]:
    """Rename ``tmp`` onto ``target`` when the block succeeds; on any failure remove ``tmp``
    (leaving ``target`` untouched) and turn an OSError into a one-line ExportError."""
    try:
        yield
        os.replace(tmp, target)
    except BaseException as exc:
        _remove_quietly(tmp)
        if isinstance(exc, OSError):
            raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
        raise
    _fsync_directory(target.parent)


def _create_temp_beside(target: Path, suffix: str = "") -> tuple[Path, int]:
    """Create an empty, exclusively owned temporary file next to ``target``; (path, fd)."""
    directory = target.parent
    while True:
        # A hidden name so that directory listings and globs (*.glb) do not pick it up.
        tmp = directory / f".{target.name}.{secrets.token_hex(6)}.tmp{suffix}"
        try:
            # os.open with mode 0o666 lets the umask decide the final permissions, as a plain
            # open() would (tempfile.mkstemp would force 0o600 on the finished file).
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
        return tmp, fd


def _reason(exc: OSError, target: Path) -> str:
    if isinstance(exc, FileNotFoundError) and not target.parent.is_dir():
        return f"directory {target.parent} does not exist"
    return exc.strerror or str(exc)


def _remove_quietly(tmp: Path) -> None:
    try:
        tmp.unlink()
    except FileNotFoundError:
        pass
    except OSError:
        # Cleanup must never hide the error that got us here.
        pass


def _fsync_directory(directory: Path) -> None:
    """Make the rename itself durable; best effort (not every platform can open a directory)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
