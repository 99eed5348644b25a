"""The command line imports only what the requested outputs need.

clifford (seconds to import) serves only as the tests' reference; a GLB build needs neither the
ray tracer, nor USD, nor the libraries that write other formats, nor pygltflib (the GLB writer
writes its JSON itself), nor OpenSSL's bindings, nor importlib.metadata (with email, socket and
csv: the version comes from cgamesh.__version__); and a build at a fixed resolution (every
centreline run) needs no numpy.ma either (numpy 2's np.unique imports it to look for a mask; the
tolerance planner still calls np.unique). Each import is resident memory, a large share of a
small input's peak.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "kb_tube.yaml"
NEVER_FOR_GLB = ("clifford", "numba", "cgamesh.tracer", "pxr", "trimesh", "xatlas", "pymeshlab", "matplotlib",
                 "dask", "distributed", "cgamesh.batching", "pygltflib", "dataclasses_json", "marshmallow",
                 "_hashlib", "hmac", "importlib.metadata", "email")
NEVER_AT_A_FIXED_RESOLUTION = NEVER_FOR_GLB + ("numpy.ma",)

PROBE = """
import json, sys
from cgamesh_cli.main import main
status = main(sys.argv[1:])
print(json.dumps({"status": status, "modules": sorted(sys.modules)}))
"""


def run_build(*arguments: str) -> dict:
    result = subprocess.run([sys.executable, "-c", PROBE, *arguments], capture_output=True, text=True,
                            check=True, timeout=120)
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_a_glb_build_imports_no_reference_tracer_usd_or_other_writers(tmp_path):
    report = run_build(str(EXAMPLE), "-o", str(tmp_path / "tube.glb"), "-q", "--around", "8", "--along", "16")
    assert report["status"] == 0
    assert forbidden(report["modules"], NEVER_AT_A_FIXED_RESOLUTION) == []


def test_a_tolerance_build_imports_nothing_more(tmp_path):
    report = run_build(str(EXAMPLE), "-o", str(tmp_path / "tube.glb"), "-q", "--tolerance", "0.01")
    assert report["status"] == 0
    assert forbidden(report["modules"]) == []


def forbidden(modules: list[str], never: tuple[str, ...] = NEVER_FOR_GLB) -> list[str]:
    return [name for name in modules if any(name == n or name.startswith(n + ".") for n in never)]


def test_an_swc_build_imports_no_tractography_or_boolean_library(tmp_path):
    source = tmp_path / "neuron.swc"
    source.write_text("1 1 0 0 0 1 -1\n2 3 0 0 3 0.5 1\n3 3 0 1 6 0.5 2\n4 3 1 0 6 0.5 2\n")
    report = run_build(str(source), "-o", str(tmp_path / "neuron.glb"), "-q", "--color-by", "radius")
    assert report["status"] == 0
    assert forbidden(report["modules"], NEVER_AT_A_FIXED_RESOLUTION) == []
    assert [m for m in report["modules"] if m.split(".")[0] in ("nibabel", "trx", "manifold3d")] == []
