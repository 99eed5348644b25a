"""The README's quick-start and test commands are the ones CI runs, in the README's order, and
the quick start installs no more than meshing needs."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    quick_start = text[text.index("## Quick start"):text.index("## The command line")]
    return [line.strip() for line in quick_start.splitlines() if line.startswith("    python -m pip install")]


def test_ci_runs_exactly_the_readme_commands_in_order():
    commands = readme_commands()
    assert commands == ['python -m pip install . && cgamesh examples/kb_tube.yaml -o kb_tube.glb',
                        'python -m pip install ".[test]" && npm ci --prefix tests/tools && python -m pytest -q']
    script = (ROOT / ".ci" / "run").read_text()
    run_lines = [line.strip() for line in script.splitlines() if line.strip().startswith("python -m pip install")]
    assert len(run_lines) == 2
    for command, line in zip(commands, run_lines):
        assert line.startswith(command), (command, line)


def test_the_quick_start_installs_only_the_core_dependencies():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    names = {re.split(r"[<>=\[ ;]", d)[0].lower() for d in project["dependencies"]}
    assert names == {"numpy", "pyyaml", "trimesh"}  # the GLB writer writes its JSON itself
    assert not names & {"clifford", "numba", "matplotlib", "usd-core", "pymeshlab"}
