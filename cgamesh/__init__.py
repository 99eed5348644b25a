"""cgamesh: meshes of surfaces interpolated between CGA circles and point pairs."""


def __getattr__(name):
    # cgamesh.batch(...) without importing the batch package (and Dask) with cgamesh itself.
    if name == "batch":
        import importlib

        return importlib.import_module("cgamesh.batch")
    raise AttributeError(f"module 'cgamesh' has no attribute {name!r}")
