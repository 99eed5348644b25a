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
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            # Without fsync the rename can reach the disk before the data does, and a crash
            # would leave an empty or partial file under the final name.
            os.fsync(f.fileno())
        os.replace(tmp, target)
    except BaseException as exc:
        _remove_quietly(tmp)
        if isinstance(exc, OSError):
            raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
        raise
    _fsync_directory(target.parent)


def _create_temp_beside(target: Path) -> tuple[Path, int]:
    """Create an empty, exclusively owned temporary file next to ``target``; (path, fd)."""
    directory = target.parent
    while True:
        # A hidden name so that directory listings and globs (*.glb) do not pick it up.
        tmp = directory / f".{target.name}.{secrets.token_hex(6)}.tmp"
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
