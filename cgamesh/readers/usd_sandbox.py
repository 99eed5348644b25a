"""USD files read in a child process, because usd-core itself does not survive every file.

Damaged crate (.usdc) files make usd-core abort the process (SIGABRT from C++) or spend
minutes decompressing an array of billions of elements; no Python code around the call can
catch either. So ``read_usd`` runs the reading (``readback.read_usd_here``) in a child Python
process (``usd_child``) with an address-space limit and a time limit; the child returns the meshes' arrays
(with their colours and attributes) in a temporary .npz file (no pickles), or one line of error with exit status 2. A child killed
by a signal, out of memory or out of time becomes one ``UnreadableFileError`` line too.

    python -m cgamesh.readers.usd_child FILE OUT.npz LIMIT     (the child's side)
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
            result = subprocess.run([sys.executable, "-m", "cgamesh.readers.usd_child", name, out, str(limit)],
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
