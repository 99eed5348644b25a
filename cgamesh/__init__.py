"""Meshes of surfaces interpolated between CGA circles and point pairs, and tubes along real
centrelines (neuron skeletons, tractograms, arrays).

``cgamesh.load(path, **options)`` and ``cgamesh.tubes(polylines, radii, parents, **options)``
(cgamesh.api) return a ``Meshes``; ``cgamesh.batch(inputs, outdir, client=None, **options)``
(cgamesh.batching) meshes whole datasets on Dask. Importing the package stays light: those
modules (and Dask) are imported on first use.

The inputs they read are the table of cgamesh.inputs.formats; the options they take, and the
command line's flags, the table of cgamesh.options; what the writers are told,
cgamesh.export.options.WriteOptions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cgamesh.api import Meshes, load, tubes
    from cgamesh.batching import batch

__all__ = ["Meshes", "batch", "load", "tubes"]

# The one place the version is written (pyproject.toml reads it from here): a GLB records it
# in its generator string on every write, and importlib.metadata, which would find it in the
# installed distribution, costs a GLB run about 2 MB resident (email, socket, csv) and a read
# of the distribution's metadata.
__version__ = "0.1.0"


def __getattr__(name: str):
    if name == "batch":
        from cgamesh.batching import batch

        return batch
    if name in __all__:
        from cgamesh import api

        return getattr(api, name)
    raise AttributeError(f"module 'cgamesh' has no attribute {name!r}")
