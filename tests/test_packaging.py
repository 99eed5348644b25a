"""pyproject.toml lists its packages by hand: every package directory must be in that list; the
version is written once, in cgamesh/__init__.py, and read from there by the build and at run time."""

from __future__ import annotations

import tomllib
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_package_directory_is_installed():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    package_dir = config.get("package-dir", {})
    on_disk = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "cgamesh").rglob("__init__.py")}
    on_disk |= {name for name, folder in package_dir.items() if (ROOT / folder / "__init__.py").is_file()}
    assert on_disk <= set(config["packages"]), f"add to [tool.setuptools] packages: {sorted(on_disk - set(config['packages']))}"


def test_the_version_has_one_source():
    import cgamesh

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "cgamesh.__version__"}
    # the installed distribution's metadata was built from the same attribute
    assert metadata.version("cgamesh") == cgamesh.__version__
