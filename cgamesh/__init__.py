"""Meshes of surfaces interpolated between CGA circles and point pairs, and tubes along real
centrelines (neuron skeletons, tractograms, arrays).

``cgamesh.load(path, **options)`` and ``cgamesh.tubes(polylines, radii, parents, **options)``
(cgamesh.api) return a ``Meshes``. Importing the package stays light: the API module is
imported on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cgamesh.api import Meshes, load, tubes

__all__ = ["Meshes", "load", "tubes"]


def __getattr__(name: str):
    if name in __all__:
        from cgamesh import api

        return getattr(api, name)
    raise AttributeError(f"module 'cgamesh' has no attribute {name!r}")
