"""Calls into the format libraries (usd-core, trimesh) that may fail on a malformed file.

usd-core prints its diagnostics to the process's stderr from C++ and raises exceptions with
multi-line messages; trimesh logs warnings and raises whatever its parsers raise. A reader
wraps each call in ``quiet_library``: file descriptor 2 goes to a temporary file for the
duration (so the user sees no diagnostics), Python warnings and log records are held back,
and any exception becomes one ``UnreadableFileError`` line naming the file, with the first
line of the library's own message.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

from cgamesh.errors import CgameshError
from cgamesh.readers.files import UnreadableFileError

MESSAGE_CHARACTERS = 160


def first_line(text: str) -> str:
    """The first non-blank line of a message, shortened to MESSAGE_CHARACTERS."""
    for line in text.splitlines():
        line = line.strip()
        if line:
            return line if len(line) <= MESSAGE_CHARACTERS else line[:MESSAGE_CHARACTERS - 3] + "..."
    return ""


def _message(error: BaseException) -> str:
    """str(error), which for usd-core's errors may itself fail (bytes of the file that are not
    UTF-8 quoted in the message)."""
    try:
        return str(error)
    except Exception:  # noqa: BLE001 (a message that cannot be formatted: the caller falls back)
        return ""


@contextmanager
def quiet_library(label: str, library: str = "the reader") -> Iterator[None]:
    """Run the block with the library's diagnostics captured; an exception from it becomes
    ``UnreadableFileError("LABEL: LIBRARY cannot read it: FIRST LINE")``."""
    with tempfile.TemporaryFile() as captured:
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(captured.fileno(), 2)
        previous = logging.root.manager.disable
        logging.disable(logging.CRITICAL)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                yield
        except CgameshError:
            raise
        except (Exception, MemoryError, RecursionError) as error:  # noqa: B014 (named for the reader)
            sys.stderr.flush()
            captured.seek(0)
            detail = first_line(_message(error)) or first_line(captured.read(4096).decode("utf-8", "replace"))
            raise UnreadableFileError(f"{label}: {library} cannot read it: {detail or type(error).__name__}") from None
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            logging.disable(previous)
