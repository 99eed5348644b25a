"""USD files read in a child process, because usd-core itself does not survive every file.

Damaged crate (.usdc) files make usd-core abort the process (SIGABRT from C++) or spend
minutes decompressing an array of billions of elements; no Python code around the call can
catch either. So ``read_usd`` runs the reading (``readback.read_usd_here``) in a child Python
process with an address-space limit and a time limit; the child returns the meshes' arrays
(with their colours and attributes) in a temporary .npz file (no pickles), or one line of error with exit status 2. A child killed
by a signal, out of memory or out of time becomes one ``UnreadableFileError`` line too.

    python -m cgamesh.readers.usd_sandbox FILE OUT.npz LIMIT     (the child's side)
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile

import numpy as np

from cgamesh.readers.files import MAX_FILE_BYTES, UnreadableFileError

# The child's limits: seconds, and address space beyond what the arrays may take (usd-core
# and Python map about a gigabyte of libraries and pools).
USD_SECONDS = 300
USD_BASE_ADDRESS_SPACE = 3 << 30
FIELDS = ("positions", "normals", "uvs", "faces")


def read_usd(path, limit: int = MAX_FILE_BYTES) -> list:
    """The meshes of a USD file, as ``readback.read_usd_here`` reads them, read in a child."""
    from cgamesh.meshing.mesh import SurfaceMesh

    name = os.fsdecode(path)
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "meshes.npz")
        import resource

        space = USD_BASE_ADDRESS_SPACE + 4 * limit
        _, hard = resource.getrlimit(resource.RLIMIT_AS)
        if hard != resource.RLIM_INFINITY:
            space = min(space, hard)  # a process may lower its limit, never raise it past the hard one

        def limits():
            resource.setrlimit(resource.RLIMIT_AS, (space, hard))

        try:
            result = subprocess.run([sys.executable, "-m", "cgamesh.readers.usd_sandbox", name, out, str(limit)],
                                    capture_output=True, text=True, errors="replace", timeout=USD_SECONDS,
                                    preexec_fn=limits, env=_child_environment())
        except subprocess.TimeoutExpired:
            raise UnreadableFileError(f"{name}: usd-core did not finish reading it within {USD_SECONDS} s") from None
        if result.returncode == 2 and result.stdout.strip():
            raise UnreadableFileError(result.stdout.strip().splitlines()[0])
        if result.returncode < 0:
            what = signal.Signals(-result.returncode).name if -result.returncode in signal.valid_signals() else ""
            raise UnreadableFileError(f"{name}: usd-core crashed reading it ({what or f'signal {-result.returncode}'})")
        if result.returncode != 0 or not os.path.exists(out):
            raise UnreadableFileError(f"{name}: usd-core could not read it (exit status {result.returncode})")
        with np.load(out, allow_pickle=False) as stored:
            names = [str(n) for n in stored["names"]]
            sided = stored["double_sided"]
            return [SurfaceMesh(n, *(stored[f"{k}_{field}"] for field in FIELDS), bool(sided[k]),
                                **_channels(stored, k)) for k, n in enumerate(names)]


def _channels(stored, k: int) -> dict:
    """Mesh ``k``'s colors and attributes from the child's .npz (attribute names are stored
    in an array of their own: a primvar name need not be a valid archive member name)."""
    colors = stored[f"{k}_colors"] if f"{k}_colors" in stored.files else None
    attributes = None
    if f"{k}_attribute_names" in stored.files:
        names = [str(n) for n in stored[f"{k}_attribute_names"]]
        attributes = {n: stored[f"{k}_attribute_{j}"] for j, n in enumerate(names)}
    return {"colors": colors, "attributes": attributes}


def _child_environment() -> dict:
    """The parent's environment, with its import path (so the child imports this cgamesh)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    return env


def main(argv: list[str]) -> int:
    from cgamesh.errors import CgameshError
    from cgamesh.readers.readback import read_usd_here

    name, out, limit = argv[0], argv[1], int(argv[2])
    try:
        meshes = read_usd_here(name, limit)
    except CgameshError as error:
        print(str(error).replace("\n", " "))
        return 2
    except MemoryError:
        print(f"{name}: reading it needs more memory than the reader allows")
        return 2
    arrays = {"names": np.array([m.name for m in meshes], dtype=str),
              "double_sided": np.array([m.double_sided for m in meshes], dtype=bool)}
    for k, mesh in enumerate(meshes):
        for field in FIELDS:
            arrays[f"{k}_{field}"] = np.asarray(getattr(mesh, field))
        if mesh.colors is not None:
            arrays[f"{k}_colors"] = np.asarray(mesh.colors)
        if mesh.attributes:
            arrays[f"{k}_attribute_names"] = np.array(list(mesh.attributes), dtype=str)
            for j, values in enumerate(mesh.attributes.values()):
                arrays[f"{k}_attribute_{j}"] = np.asarray(values)
    np.savez(out, **arrays)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
