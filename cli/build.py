"""``cgamesh SCENE.yaml -o OUT.glb``: mesh every surface of a scene and export them."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError

WRITERS = (".glb",)


def _whole_number(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 2, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh",
        description="Mesh the CGA evolved surfaces of a scene file and export them.",
    )
    parser.add_argument("scene", help="the YAML scene file (format version 1)")
    parser.add_argument("-o", "--output", required=True, help="output file: .glb")
    parser.add_argument("--around", type=_whole_number, help="vertices around every circle (overrides the file)")
    parser.add_argument("--along", type=_whole_number, help="rings along every surface (overrides the file)")
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    return parser


def run(args: argparse.Namespace) -> str:
    """Build and write; returns the summary line."""
    from cgamesh.export.gltf import write_glb
    from cgamesh.pipeline import Resolution, mesh_scene
    from cgamesh.progress import Progress
    from cgamesh.scene import load_scene

    output = Path(args.output)
    if output.suffix.lower() not in WRITERS:
        raise InvalidInputError(
            f"{output}: unknown output format {output.suffix or '(no extension)'!r}; expected one of {', '.join(WRITERS)}"
        )
    start = time.perf_counter()
    scene = load_scene(args.scene)
    with Progress(len(scene.surfaces), enabled=not args.quiet) as progress:
        meshes = mesh_scene(scene, Resolution(args.around, args.along), progress=progress.advance)
    written = write_glb(output, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit,
                        source_units=scene.units)
    seconds = time.perf_counter() - start
    vertices = sum(mesh.vertex_count for mesh, _ in meshes)
    triangles = sum(mesh.triangle_count for mesh, _ in meshes)
    return (f"{output}: {len(meshes)} surface{'s' if len(meshes) != 1 else ''}, {vertices} vertices, "
            f"{triangles} triangles, {seconds:.2f} s, {written} bytes")
