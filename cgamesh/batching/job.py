"""One input, one task: what a worker does for each input of a batch.

``mesh_input`` is the only place where the batch engine meets the meshing: it reads one input
file, meshes it with the single-file command's options (a plain dict, as that command's parser
produced it) and writes every output, each atomically (temporary file, then rename). It does
exactly what ``cgamesh SCENE.yaml -o OUT ...`` does. ``run_job`` wraps it into the record the
engine collects: a user-level failure (a malformed file, an impossible geometry, a refused
size) becomes a failed record with a one-line reason; anything else is raised, so the
scheduler retries the task.
"""

from __future__ import annotations

import hashlib
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from cgamesh.errors import CgameshError


def check_options(options: Mapping) -> None:
    """Refuse unknown or contradictory options once, before any input is meshed (the names
    and the refused combinations are those of the table in cgamesh.options)."""
    from cgamesh.options import check_batch

    check_batch(options)


def mesh_input(path: Path, outputs: Sequence[Path], options: Mapping) -> dict:
    """Mesh the input file at ``path`` (a scene or centrelines, by its format in the input
    table) through ``cgamesh.load`` with the given options that its kind takes, and write it to
    every one of ``outputs`` (the format of each by its extension); returns ``{"vertices": ...,
    "bytes": ..., "left_out": ...}`` (bytes of all outputs; centreline segments that could not
    be meshed)."""
    from cgamesh.api import load
    from cgamesh.inputs.formats import format_of
    from cgamesh.options import for_input, given, write_keywords

    meshes = load(path, **for_input(options, format_of(path).kind))
    writing = {name: value for name, value in given(options).items() if name in write_keywords()}
    written = [meshes.export(output, **writing) for output in outputs]
    return {"vertices": sum(mesh.vertex_count for mesh, _ in meshes.surfaces), "bytes": sum(written),
            "left_out": len(meshes.skipped)}


def run_job(source: str, outputs: Sequence[str], options: Mapping) -> dict:
    """The task of one input: hash it, mesh it, write its outputs. Returns a dict with
    ``status`` ("done" or "failed"), ``reason``, ``sha256``, ``seconds``, ``vertices``,
    ``bytes``, ``cpu_seconds`` (the processor time it took, which other load on the machine
    does not inflate) and ``worker`` (the process id that did it)."""
    start, cpu_start = time.perf_counter(), time.process_time()
    record = {"status": "done", "reason": "", "sha256": "", "vertices": 0, "bytes": 0, "worker": os.getpid()}
    try:
        record["sha256"] = file_sha256(source)
        for output in outputs:
            Path(output).parent.mkdir(parents=True, exist_ok=True)
            remove_stale_temporaries(Path(output))
        record.update(mesh_input(Path(source), [Path(o) for o in outputs], options))
        left_out = record.pop("left_out")
        if left_out:  # the single-file command's --keep-going: the rest is meshed, the gap named
            record["reason"] = f"{left_out} segment{'s' if left_out != 1 else ''} could not be meshed and were left out"
    except CgameshError as error:
        record.update(status="failed", reason=one_line(str(error)))
    except OSError as error:
        record.update(status="failed", reason=one_line(f"{error.filename or source}: {error.strerror or error}"))
    record["seconds"] = time.perf_counter() - start
    record["cpu_seconds"] = time.process_time() - cpu_start
    return record


def remove_stale_temporaries(output: Path) -> None:
    """Remove the temporary files a killed earlier run left beside ``output`` (hidden names of
    cgamesh.export.atomic: ``.NAME.<random>.tmp``); each output belongs to one task only."""
    for stale in output.parent.glob(f".{output.name}.*.tmp*"):
        stale.unlink(missing_ok=True)


def file_sha256(path: str | os.PathLike) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def one_line(text: str) -> str:
    """The first line of a message, so every failure is reported on one line."""
    lines = text.strip().splitlines()
    return lines[0] if lines else "(no message)"
