"""Optional dependencies: imported only by the feature that needs them, with a one-line error
naming the extra to install when they are missing."""

from __future__ import annotations

import importlib
from types import ModuleType

from cgamesh.errors import CgameshError


class MissingDependencyError(CgameshError):
    """A feature was asked for whose optional package is not installed."""


def require(module: str, extra: str, purpose: str) -> ModuleType:
    """``importlib.import_module(module)``, or MissingDependencyError naming ``cgamesh[extra]``."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingDependencyError(
            f"{purpose} needs the Python package {module.split('.')[0]!r}, which is not installed "
            f"({exc}); install it with: python -m pip install 'cgamesh[{extra}]'"
        ) from None
