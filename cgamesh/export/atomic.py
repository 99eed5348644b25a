"""Atomic file writes: a reader sees the old file or the complete new one, never a torn one.

The data goes to a temporary file in the target's own directory (so the final rename stays on
one file system and is atomic), is flushed and fsynced, and then replaces the target with
``os.replace``. If anything fails before that, the temporary file is removed and an existing
target is left exactly as it was.

All or nothing across files: inside ``all_or_nothing()`` every write (each output of a run and
each sidecar of each, the report) only stages its finished temporary; when the block succeeds
they are all renamed into place together, and when anything fails (an exception, SIGTERM or
SIGINT raised as an exception by the command line) every staged temporary is removed and no
target is touched. A commit (the renames of one write, or of a whole ``all_or_nothing``):

- holds an exclusive advisory lock (``fcntl.flock``) on each target's directory, taken in
  sorted order, so two processes committing into one folder take turns: a .gltf and its .bin
  (an .obj and its .mtl) always come from the same run, never a mix of two;
- blocks SIGINT and SIGTERM while it renames (a signal then arrives after the commit);
- keeps a hard link to each old target first, so that if a rename fails half way the targets
  already replaced get their old files back.

Every temporary file alive is listed in ``LIVE_TEMPORARIES``; ``remove_live_temporaries()``
is the command line's last resort on an interrupt.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from cgamesh.errors import ExportError

try:
    import fcntl
except ImportError:  # not on Windows: commits there are not serialised between processes
    fcntl = None

LIVE_TEMPORARIES: set[Path] = set()
_STAGES: list[list[tuple[Path, Path]]] = []  # open all_or_nothing blocks, innermost last
_SIGNALS = {signal.SIGINT, signal.SIGTERM}


def _token() -> str:
    """12 random hex digits naming a temporary file. os.urandom, as ``secrets.token_hex`` uses,
    without ``secrets``' import of hmac and OpenSSL (3.5 MB resident, a third of a small
    neuron's GLB)."""
    return os.urandom(6).hex()


@contextmanager
def all_or_nothing() -> Iterator[None]:
    """Stage every atomic write made inside the block; rename them all into place when it
    succeeds, remove them all when it fails (see the module doc)."""
    staged: list[tuple[Path, Path]] = []
    _STAGES.append(staged)
    try:
        yield
    except BaseException:
        _STAGES.remove(staged)
        for tmp, _ in staged:
            _remove_quietly(tmp)
        raise
    _STAGES.remove(staged)
    if _STAGES:  # nested: the outer block commits
        _STAGES[-1].extend(staged)
        return
    try:
        _commit(staged)
    except BaseException:
        for tmp, _ in staged:
            _remove_quietly(tmp)
        raise


def remove_live_temporaries() -> None:
    """Remove every temporary file this process has created and not yet renamed or removed."""
    for tmp in list(LIVE_TEMPORARIES):
        _remove_quietly(tmp)


def _finish(pairs: list[tuple[Path, Path]]) -> None:
    """The temporaries of one write are complete: stage them, or commit them now."""
    if _STAGES:
        _STAGES[-1].extend(pairs)
    else:
        _commit(pairs)


def _commit(pairs: list[tuple[Path, Path]]) -> None:
    """Rename every (temporary, target) into place, under the directories' locks, signals held
    back, rolling back on a failed rename; an OSError becomes a one-line ExportError."""
    if not pairs:
        return
    directories = sorted({str(target.parent.resolve()) for _, target in pairs})
    blocked = _block_signals()
    locks = []
    backups: list[tuple[Path, Path]] = []  # (hard link to the old file, target)
    replaced: list[Path] = []
    try:
        for directory in directories:
            locks.append(_lock(directory))
        for _, target in pairs:
            backup = _backup(target)
            if backup is not None:
                backups.append((backup, target))
        for tmp, target in pairs:
            try:
                os.replace(tmp, target)
            except OSError as exc:
                raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
            LIVE_TEMPORARIES.discard(tmp)
            replaced.append(target)
    except BaseException:
        old = {target: backup for backup, target in backups}
        for target in replaced:  # put back what was there
            if target in old:
                try:
                    os.replace(old.pop(target), target)
                except OSError:
                    pass
            else:
                _remove_quietly(target)
        raise
    finally:
        for backup, _ in backups:
            _remove_quietly(backup)
        for fd in locks:
            os.close(fd)  # releases the lock
        _unblock_signals(blocked)
    for directory in directories:
        _fsync_directory(Path(directory))


def _lock(directory: str) -> int:
    """An exclusive flock on the directory itself (no lock file is left behind); its fd."""
    fd = os.open(directory, os.O_RDONLY)
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            pass  # a file system without flock: the renames are still each atomic
    return fd


def _backup(target: Path) -> Path | None:
    """A hard link to the existing target beside it (None: no target, or no hard links here)."""
    if not target.is_file():
        return None
    while True:
        link = target.parent / f".{target.name}.{_token()}.old"
        try:
            os.link(target, link)
        except FileExistsError:
            continue
        except OSError:
            return None
        LIVE_TEMPORARIES.add(link)
        return link


def _block_signals():
    if hasattr(signal, "pthread_sigmask"):
        return signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    return None


def _unblock_signals(previous) -> None:
    if previous is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


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
        _finish(list(zip(temps, targets)))
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
        _finish([(tmp, target)])
    except BaseException as exc:
        _remove_quietly(tmp)
        if isinstance(exc, OSError):
            raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
        raise


def _create_temp_beside(target: Path, suffix: str = "") -> tuple[Path, int]:
    """Create an empty, exclusively owned temporary file next to ``target``; (path, fd)."""
    directory = target.parent
    while True:
        # A hidden name so that directory listings and globs (*.glb) do not pick it up.
        tmp = directory / f".{target.name}.{_token()}.tmp{suffix}"
        blocked = _block_signals()  # an interrupt between creating and listing it would leak it
        try:
            # os.open with mode 0o666 lets the umask decide the final permissions, as a plain
            # open() would (tempfile.mkstemp would force 0o600 on the finished file).
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
            LIVE_TEMPORARIES.add(tmp)
        except FileExistsError:
            continue
        except OSError as exc:
            raise ExportError(f"cannot write {target}: {_reason(exc, target)}") from exc
        finally:
            _unblock_signals(blocked)
        return tmp, fd


def _reason(exc: OSError, target: Path) -> str:
    if isinstance(exc, FileNotFoundError) and not target.parent.is_dir():
        return f"directory {target.parent} does not exist"
    return exc.strerror or str(exc)


def _remove_quietly(tmp: Path) -> None:
    LIVE_TEMPORARIES.discard(tmp)
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
