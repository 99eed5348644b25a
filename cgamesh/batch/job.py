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

from cgamesh.errors import CgameshError, InvalidInputError

# File extensions a folder given as input is searched for (lower case).
INPUT_EXTENSIONS: tuple[str, ...] = (".yaml", ".yml")
# The meshing options mesh_input understands: the single-file command's (cli/build.py).
OPTION_NAMES: frozenset[str] = frozenset({"around", "along", "tolerance", "tangents", "quantize"})


def check_options(options: Mapping) -> None:
    """Refuse unknown or contradictory options once, before any input is meshed."""
    unknown = sorted(set(options) - OPTION_NAMES)
    if unknown:
        raise InvalidInputError(f"unknown meshing option{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}; "
                                f"expected some of {', '.join(sorted(OPTION_NAMES))}")
    if options.get("tolerance") is not None and (options.get("around") is not None or options.get("along") is not None):
        raise InvalidInputError("--tolerance cannot be combined with --around or --along")


def mesh_input(path: Path, outputs: Sequence[Path], options: Mapping) -> dict:
    """Mesh the input file at ``path`` and write it to every one of ``outputs`` (the format of
    each by its extension); returns ``{"vertices": ..., "bytes": ...}`` (bytes of all outputs)."""
    from cgamesh.export.registry import write
    from cgamesh.inputs.scene import load_scene
    from cgamesh.pipeline import Resolution, mesh_scene

    scene = load_scene(path)
    resolution = Resolution(options.get("around"), options.get("along"), options.get("tolerance"))
    tangents = bool(options.get("tangents"))
    meshes = mesh_scene(scene, resolution, tangents=tangents)
    written = [write(output, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit, source_units=scene.units,
                     tangents=tangents, quantize=bool(options.get("quantize"))) for output in outputs]
    return {"vertices": sum(mesh.vertex_count for mesh, _ in meshes), "bytes": sum(written)}


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
