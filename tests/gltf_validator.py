"""Run the Khronos glTF-Validator (the npm package pinned in tests/tools) on an exported file.

Install it with ``npm ci --prefix tests/tools``; the ``gltf_validator`` fixture in conftest.py
skips loudly when it is missing locally and fails under CI.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

TOOLS_DIR = Path(__file__).resolve().parent / "tools"
SCRIPT = TOOLS_DIR / "validate_gltf.mjs"
PACKAGE = TOOLS_DIR / "node_modules" / "gltf-validator" / "package.json"


def unavailable_reason() -> str | None:
    """Why the validator cannot run here, or None when it can."""
    if shutil.which("node") is None:
        return "node is not on PATH: the Khronos glTF-Validator cannot run (install Node.js 20)"
    if not PACKAGE.is_file():
        return f"the Khronos glTF-Validator is not installed: run `npm ci --prefix {_shown(TOOLS_DIR)}`"
    return None


def validate_gltf(path: str | os.PathLike[str]) -> dict:
    """The validator's JSON report on a .glb / .gltf file (see report["issues"])."""
    result = subprocess.run(
        ["node", str(SCRIPT), os.fspath(path)], capture_output=True, text=True, timeout=300, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"glTF-Validator failed on {path} (exit {result.returncode}): {result.stderr.strip()}")
    return json.loads(result.stdout)


def validate_many(paths) -> list[dict]:
    """The validator's reports on several files, from one node process (faster than one each)."""
    paths = [os.fspath(p) for p in paths]
    if len(paths) == 1:
        return [validate_gltf(paths[0])]
    result = subprocess.run(
        ["node", str(SCRIPT), *paths], capture_output=True, text=True, timeout=600, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"glTF-Validator failed (exit {result.returncode}): {result.stderr.strip()}")
    return json.loads(result.stdout)


def issues_text(report: dict) -> str:
    """Every issue of a report, one per line, for an assertion message."""
    issues = report["issues"]
    lines = [
        f"{issues['numErrors']} errors, {issues['numWarnings']} warnings, "
        f"{issues['numInfos']} infos, {issues['numHints']} hints"
    ]
    severity = {0: "error", 1: "warning", 2: "info", 3: "hint"}
    for m in issues["messages"]:
        lines.append(f"  {severity.get(m['severity'], m['severity'])} {m['code']} at {m.get('pointer', '-')}: {m['message']}")
    return "\n".join(lines)


def assert_clean(report: dict) -> None:
    """No error and no warning (infos and hints are allowed, and shown when this fails)."""
    issues = report["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues_text(report)


def _shown(path: Path) -> str:
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)
