"""Real centreline files that installed packages ship, found without importing the packages.

- nibabel's test data: .trk and .tck files (MIT licence, in the nibabel package).
- dipy's data files present without download: tracks300.trk, a fornix of 300 streamlines
  (BSD licence).
- navis' example neurons: five olfactory projection neurons of the Janelia hemibrain data set
  (Scheffer et al., eLife 2020), SWC in 8 nm voxel units. navis is GPL-3 licensed and does not
  state a separate licence for the files, so they are read where navis installed them, not copied.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest


def package_dir(name: str) -> Path:
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        pytest.fail(f"the test dependency {name!r} is not installed (pip install '.[test]')", pytrace=False)
    return Path(list(spec.submodule_search_locations)[0])


def nibabel_file(name: str) -> Path:
    return package_dir("nibabel") / "tests" / "data" / name


def fornix() -> Path:
    return package_dir("dipy") / "data" / "files" / "tracks300.trk"


def neurons() -> list[Path]:
    files = sorted((package_dir("navis") / "data" / "swc").glob("*.swc"))
    assert len(files) == 5, files
    return files


def smallest_neuron() -> Path:
    return min(neurons(), key=lambda p: p.stat().st_size)
