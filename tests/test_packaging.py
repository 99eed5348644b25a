"""pyproject.toml lists its packages by hand: every package directory must be in that list."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_package_directory_is_installed():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    package_dir = config.get("package-dir", {})
    on_disk = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "cgamesh").rglob("__init__.py")}
    on_disk |= {name for name, folder in package_dir.items() if (ROOT / folder / "__init__.py").is_file()}
    assert on_disk <= set(config["packages"]), f"add to [tool.setuptools] packages: {sorted(on_disk - set(config['packages']))}"
