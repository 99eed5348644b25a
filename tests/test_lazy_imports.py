"""The command line imports only what the requested outputs need.

clifford (seconds to import) serves only as the tests' reference; a GLB build needs neither the
ray tracer, nor USD, nor the libraries that write other formats.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "kb_tube.yaml"
NEVER_FOR_GLB = ("clifford", "numba", "cgamesh.tracer", "pxr", "trimesh", "xatlas", "pymeshlab", "matplotlib",
                 "dask", "distributed", "cgamesh.batch")

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
    assert forbidden(report["modules"]) == []


def test_a_tolerance_build_imports_nothing_more(tmp_path):
    report = run_build(str(EXAMPLE), "-o", str(tmp_path / "tube.glb"), "-q", "--tolerance", "0.01")
    assert report["status"] == 0
    assert forbidden(report["modules"]) == []


def forbidden(modules: list[str]) -> list[str]:
    return [name for name in modules if any(name == n or name.startswith(n + ".") for n in NEVER_FOR_GLB)]
