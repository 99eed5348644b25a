"""``--report REPORT.json``: the mesh-quality report of the meshes a build made (cgamesh.quality)."""

from __future__ import annotations


def write_report(path: str, meshes, source: str) -> list[str]:
    """Write the quality report of ``meshes`` as JSON at ``path`` (atomically); its failures."""
    from cgamesh.export.atomic import atomic_write
    from cgamesh.quality import report

    result = report(meshes, str(source))
    with atomic_write(path) as f:
        f.write(result.to_json().encode() + b"\n")
    return result.failures()
