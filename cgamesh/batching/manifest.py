"""The record of what a batch has done in its output folder: ``cgamesh-manifest.json``.

One entry per input, keyed by the input's name (its path relative to the inputs' common
folder): its path, sha256, the meshing options, the tool version, status and reason, seconds,
vertices, bytes and outputs (relative to the output folder). A rerun skips an input whose
entry says done with the same hash, options and version and whose outputs all exist and are
newer than the input. The file is replaced atomically, so a killed run leaves the last
complete version.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

from cgamesh import __version__
from cgamesh.errors import InvalidInputError

MANIFEST_NAME = "cgamesh-manifest.json"
FORMAT_VERSION = 1


def tool_version() -> str:
    return f"cgamesh {__version__}"


def normalised(options: Mapping) -> dict:
    """Options as the manifest stores them: only those given (cgamesh.options.given: not None,
    a switch on), so the command line's and the Python API's same request are stored alike, in
    JSON types with sorted keys, so they compare equal after a round trip through the file."""
    from cgamesh.options import given

    return json.loads(json.dumps(given(options), sort_keys=True))


class Manifest:
    """The entries of one output folder's manifest, read at the start and saved as tasks finish."""

    def __init__(self, outdir: str | os.PathLike):
        self.path = Path(outdir) / MANIFEST_NAME
        self.entries: dict[str, dict] = {}
        if self.path.is_file():
            try:
                document = json.loads(self.path.read_text(encoding="utf-8"))
                self.entries = dict(document["inputs"])
            except (ValueError, KeyError, TypeError) as error:
                raise InvalidInputError(f"{self.path}: not a cgamesh manifest ({error}); remove it or "
                                        "choose another output folder") from None

    def is_current(self, name: str, input_path: Path, outputs, options: dict, version: str, sha256) -> bool:
        """Whether the entry ``name`` says the input was meshed into ``outputs`` as asked now.
        ``sha256`` is called (it reads the whole input) only when everything cheaper agrees."""
        entry = self.entries.get(name)
        if not entry or entry.get("status") != "done" or entry.get("options") != options or entry.get("tool") != version:
            return False
        try:
            input_time = input_path.stat().st_mtime
            if any(Path(o).stat().st_mtime < input_time for o in outputs):
                return False
        except OSError:
            return False
        return entry.get("sha256") == sha256()

    def record(self, name: str, entry: dict) -> None:
        self.entries[name] = entry

    def save(self) -> None:
        from cgamesh.export.atomic import atomic_write

        self.path.parent.mkdir(parents=True, exist_ok=True)
        document = {"format": FORMAT_VERSION, "inputs": dict(sorted(self.entries.items()))}
        with atomic_write(self.path) as stream:
            stream.write(json.dumps(document, indent=1).encode() + b"\n")
