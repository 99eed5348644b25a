"""The child's side of the USD sandbox (cgamesh.readers.usd_sandbox): read one file, hand back arrays.

    python -m cgamesh.readers.usd_child FILE OUT.npz LIMIT

Reads FILE with ``readback.read_usd_here`` and writes the meshes' arrays (with their colours
and attributes) to OUT.npz (no pickles), exit status 0; or prints one line of error and exits
with status 2. A crash, a signal or the time limit is the parent's to report.
"""

from __future__ import annotations

import sys

import numpy as np

from cgamesh.readers.usd_sandbox import FIELDS


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
