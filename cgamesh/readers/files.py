"""Files read by ``check`` and ``verify``, opened as if they were hostile.

A mesh file names other files (a glTF buffer's or image's ``uri``, a USD layer's sublayers
and references). Each is read only if it is a regular file inside the mesh file's own folder:

- a ``data:`` URI is decoded only in its base64 form, and only when its decoded size is
  within the limit; any other scheme (``file:``, ``http:``, ...) is refused;
- the path is percent-decoded first (``%2e%2e/x`` is ``../x``); an absolute path, a drive
  letter, a backslash, a NUL or a ``..`` component is refused;
- the resolved path (symlinks followed) must still lie inside the folder;
- the file is opened with O_NONBLOCK (a FIFO cannot block the open) and checked with fstat on
  the open descriptor (no race with a rename): devices, FIFOs, sockets and folders are
  refused, and a size over the limit is refused before anything is read.

Every refusal is an ``UnreadableFileError``, one line naming the file and what was wrong.
"""

from __future__ import annotations

import base64
import binascii
import os
import stat
from pathlib import Path
from urllib.parse import unquote

from cgamesh.errors import InvalidInputError

# Largest file (or decoded data URI) read, in bytes, without --max-memory: well above any mesh
# cgamesh writes, far below what would exhaust a machine.
MAX_FILE_BYTES = 1 << 31


def read_limit(max_memory=None) -> int:
    """The most bytes ``check`` and ``verify`` read from one file and decode from it: the budget
    of ``--max-memory`` when one is given (a size in bytes, a size string or a
    cgamesh.budget.Budget; never below the FIXED_OVERHEAD every budget allows), else
    MAX_FILE_BYTES."""
    if max_memory is None:
        return MAX_FILE_BYTES
    from cgamesh.budget import FIXED_OVERHEAD, Budget

    return max(Budget.of(max_memory).limit, FIXED_OVERHEAD)


def _over(size: int, limit: int) -> str:
    from cgamesh.budget import format_size

    return f"more than the {format_size(limit)} a read may take (--max-memory)"


class UnreadableFileError(InvalidInputError):
    """A mesh file (or a file it names) that is refused or malformed; the message names it."""


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def check_regular(path: str | os.PathLike, limit: int = MAX_FILE_BYTES, label: str | None = None) -> int:
    """The size of ``path`` if it is a regular file within ``limit`` bytes (symlinks followed);
    else UnreadableFileError (naming ``label``, default the path). For libraries that open
    the file by name themselves."""
    name = label or os.fsdecode(path)
    try:
        info = os.stat(os.fsdecode(path))
    except OSError as error:
        raise UnreadableFileError(f"{name}: cannot read: {error.strerror or error}") from None
    if not stat.S_ISREG(info.st_mode):
        raise UnreadableFileError(f"{name}: {_kind(info.st_mode)}, not a regular file")
    if info.st_size > limit:
        raise UnreadableFileError(f"{name}: {info.st_size} bytes, {_over(info.st_size, limit)}")
    return info.st_size


def read_regular(path: str | os.PathLike, limit: int = MAX_FILE_BYTES, label: str | None = None) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (see the module doc).

    ``label``: how messages name the file (default: its path).
    """
    name = os.fsdecode(path)
    label = label or name
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:
        raise UnreadableFileError(f"{label}: cannot open: {error.strerror or error}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise UnreadableFileError(f"{label}: {_kind(info.st_mode)}, not a regular file")
        if info.st_size > limit:
            raise UnreadableFileError(f"{label}: {info.st_size} bytes, {_over(info.st_size, limit)}")
        chunks, total = [], 0
        while total <= info.st_size:  # one byte more than stat said: a file that grows is refused
            chunk = os.read(fd, min(info.st_size + 1 - total, 1 << 24) or 1)
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total != info.st_size:
            raise UnreadableFileError(f"{label}: changed size while being read")
        return b"".join(chunks)
    except OSError as error:
        raise UnreadableFileError(f"{label}: cannot read: {error.strerror or error}") from None
    finally:
        os.close(fd)


def decode_data_uri(uri: str, limit: int, label: str) -> bytes:
    """The bytes of a ``data:[<type>];base64,<data>`` URI, refused when over ``limit``."""
    header, comma, payload = uri.partition(",")
    if not comma or not header.endswith(";base64"):
        raise UnreadableFileError(f"{label}: only base64 data URIs are read, got {uri[:40]!r}")
    if len(payload) // 4 * 3 > limit:
        raise UnreadableFileError(f"{label}: a data URI of about {len(payload) // 4 * 3} bytes, "
                                  f"{_over(len(payload) // 4 * 3, limit)}")
    try:
        return base64.b64decode(payload, validate=True)
    except (binascii.Error, ValueError):
        raise UnreadableFileError(f"{label}: the data URI is not valid base64") from None


def resolve_relative(folder: str | os.PathLike, reference: str, label: str) -> Path:
    """The file a relative reference (a URI or USD asset path) names inside ``folder``, or
    UnreadableFileError: see the module doc for what is refused."""
    try:
        decoded = unquote(reference, errors="strict") if "%" in reference else reference
    except UnicodeDecodeError:
        raise UnreadableFileError(f"{label}: {reference!r} is not UTF-8 once percent-decoded") from None
    if not decoded:
        raise UnreadableFileError(f"{label}: an empty file reference")
    if "\\" in decoded or "\0" in decoded:
        raise UnreadableFileError(f"{label}: {reference!r}: backslashes and NUL are not allowed in a file reference")
    if decoded.startswith("/") or (len(decoded) > 1 and decoded[1] == ":") or ":" in decoded.split("/")[0]:
        raise UnreadableFileError(f"{label}: {reference!r} is absolute or has a scheme; only files beside the "
                                  "mesh file are read")
    if ".." in decoded.split("/"):
        raise UnreadableFileError(f"{label}: {reference!r} leaves the mesh file's folder (..)")
    base = Path(os.path.realpath(folder))
    target = Path(os.path.realpath(base / decoded))
    if target != base and base not in target.parents:
        raise UnreadableFileError(f"{label}: {reference!r} resolves outside the mesh file's folder (a symlink)")
    return target


def read_reference(folder: str | os.PathLike, reference: str, limit: int, label: str) -> bytes:
    """The bytes a reference names: a base64 data URI, or a regular file inside ``folder``."""
    if reference.startswith("data:"):
        return decode_data_uri(reference, limit, label)
    return read_regular(resolve_relative(folder, reference, label), limit, f"{label} ({reference!r})")
