"""``cgamesh check FILE``: the mesh-quality report of a scene file or an exported mesh file."""

from __future__ import annotations

import argparse
from pathlib import Path
from cgamesh_cli.arguments import add_budget_option, add_option_flags, finite_number, whole_number

EXIT_QUALITY = 1  # --strict and a threshold broken


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh check",
        description="Print the mesh-quality report of a scene (.yaml, meshed first) or of an exported file "
                    "(.glb, .gltf, .usd, .usda, .usdc, .usdz, .obj, .ply, .stl).",
    )
    parser.add_argument("file", help="a scene file or an exported mesh file")
    parser.add_argument("--json", action="store_true", help="print the report as JSON instead of a table")
    parser.add_argument("--report", metavar="REPORT.json", help="also write the report as JSON to this file")
    parser.add_argument("--strict", action="store_true", help="exit 1 when a threshold is broken")
    parser.add_argument("--max-aspect", type=finite_number, help="also refuse triangles with a larger aspect ratio")
    parser.add_argument("--min-angle", type=finite_number, help="also refuse triangles with a smaller angle (degrees)")
    parser.add_argument("--max-uv-flips", type=whole_number(0), help="also refuse more triangles with flipped UVs")
    parser.add_argument("--max-normal-deviation", type=finite_number,
                        help="also refuse normals further from their faces' (degrees)")
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing (the exit status tells)")
    add_option_flags(parser, ("around", "along"))  # scene files: the table's (cgamesh.options)
    return parser


def run(args: argparse.Namespace):
    """Print the table (or JSON); returns 1 under --strict when a threshold is broken."""
    from cgamesh.quality import Thresholds, load_meshes, report

    from cgamesh.inputs.formats import InputKind, find

    path = Path(args.file)
    found = find(path)
    if found is not None and found.kind is InputKind.SCENE:
        from cgamesh.pipelines.scene import Resolution, mesh_scene

        scene = found.read(path, rendering=False)  # the rendering keys are render's and verify's
        meshes = [mesh for mesh, _ in mesh_scene(scene, Resolution(args.around, args.along), max_memory=args.max_memory)]
    else:
        from cgamesh.readers.files import read_limit

        meshes = load_meshes(path, read_limit(args.max_memory))
    limits = Thresholds(max_aspect_ratio=args.max_aspect, min_angle_degrees=args.min_angle,
                        uv_flips=args.max_uv_flips, max_normal_deviation_degrees=args.max_normal_deviation)
    result = report(meshes, str(path), limits)
    if args.report:
        from cgamesh.export.atomic import atomic_write

        with atomic_write(args.report) as f:
            f.write(result.to_json().encode() + b"\n")
    if not args.quiet:
        print(result.to_json() if args.json else result.table())
    if args.strict and result.failures():
        return EXIT_QUALITY
    return None
