"""The worker of ``compare_trees.py``: meshes jobs with one tree's code and dumps what it got.

    python compare_trees_child.py TREE_ROOT      (started by compare_trees.py with TREE_ROOT's PYTHONPATH)

Reads one JSON job a line on stdin and answers each with a RESULT line (trees.answer); whatever
the package prints goes to stderr. Only interfaces that stay across a refactor are used:

- ``api``:    ``cgamesh.load(input, **options)`` -> ``Meshes``; every surface's arrays
              (positions, normals, uvs, faces, tangents, colors, weld and every attribute) to
              ``OUT/arrays.npz`` as "SURFACE.FIELD", its name, material and flags to the answer.
- ``cli``:    ``cgamesh_cli.main.main(argv)`` with "{out}" in argv standing for OUT; the answer
              holds the exit status and stderr (OUT written as "{out}"), the files stay in OUT.
- ``export``: ``cgamesh.load(input, **options).export(OUT/NAME)`` for each NAME in argv.
- ``decode``: written files read back by ``cgamesh.readers.readback`` (glTF with its node
              transforms, USD, OBJ / PLY / STL) and dumped as ``api`` dumps a load.

A job that raises answers {"error": "Type: message"} (a refusal is compared like a mesh).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import sys
from pathlib import Path

import numpy as np

from trees import answer, check_imports

FIELDS = ("positions", "normals", "uvs", "faces", "tangents", "colors", "weld")


def dump(surfaces, target: Path) -> list[dict]:
    """Write every (mesh, material)'s arrays to ``target`` (npz); their descriptions."""
    arrays, described = {}, []
    for i, (mesh, material) in enumerate(surfaces):
        described.append({"name": mesh.name, "double_sided": bool(mesh.double_sided),
                          "max_deviation": getattr(mesh, "max_deviation", None),
                          "material": repr(material) if material is not None else None})
        for field in FIELDS:
            value = getattr(mesh, field, None)
            if value is not None:
                arrays[f"{i}.{field}"] = np.asarray(value)
        for key, value in (getattr(mesh, "attributes", None) or {}).items():
            arrays[f"{i}.attribute:{key}"] = np.asarray(value)
    np.savez(target, **arrays)
    return described


def run_api(job: dict, out: Path) -> dict:
    import cgamesh

    meshes = cgamesh.load(job["input"], **job.get("options", {}))
    surfaces = dump(meshes.surfaces, out / "arrays.npz")
    return {"surfaces": surfaces, "up": meshes.up, "units": meshes.units,
            "meters_per_unit": meshes.meters_per_unit, "skipped": list(meshes.skipped)}


def run_cli(job: dict, out: Path) -> dict:
    from cgamesh_cli.main import main

    errors = io.StringIO()
    with contextlib.redirect_stderr(errors):
        status = main([arg.replace("{out}", str(out)) for arg in job["argv"]])
    return {"status": status, "stderr": errors.getvalue().replace(str(out), "{out}")}


def run_export(job: dict, out: Path) -> dict:
    import cgamesh

    meshes = cgamesh.load(job["input"], **job.get("options", {}))
    for name in job["argv"]:
        meshes.export(out / name)
    return {"status": 0, "stderr": ""}


def run_decode(job: dict) -> dict:
    from cgamesh.readers.readback import read_gltf, read_trimesh, read_usd

    described = {}
    for source, target in job["files"]:
        suffix = Path(source).suffix.lower()
        if suffix in (".glb", ".gltf"):
            meshes = read_gltf(source, world=True)
        elif suffix.startswith(".usd"):
            meshes = read_usd(source)
        else:
            meshes = read_trimesh(source)
        described[source] = dump([(mesh, None) for mesh in meshes], Path(target))
    return {"files": described}


def run(job: dict) -> dict:
    from cgamesh.errors import CgameshError

    try:
        if job["kind"] == "decode":
            return run_decode(job)
        out = Path(job["out"])
        out.mkdir(parents=True, exist_ok=True)
        return {"api": run_api, "cli": run_cli, "export": run_export}[job["kind"]](job, out)
    except CgameshError as error:
        return {"error": f"{type(error).__name__}: {error}"}
    except Exception as error:  # a crash of the tree's code is an outcome too, compared like a refusal
        return {"error": f"{type(error).__name__}: {error}", "unexpected": True}


def main() -> None:
    root = sys.argv[1]
    protocol = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)  # anything printed, by Python or a library, goes to stderr
    check_imports(root)
    import cgamesh

    answer({"ready": True, "cgamesh": str(Path(cgamesh.__file__).parent)}, protocol)
    for line in sys.stdin:
        if line.strip():
            answer(run(json.loads(line)), protocol)


if __name__ == "__main__":
    main()
