"""``cgamesh SCENE.yaml -o OUT.glb [-o OUT.usdz ...]``: mesh every surface of a scene once and
export it to every output, each in the format of its extension (cgamesh.export.registry)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh.export.registry import WRITERS, writer_for
from cgamesh_cli import realdata
from cgamesh_cli.arguments import add_budget_option, add_option_flags, option_values
from cgamesh_cli.report import write_report

EXIT_QUALITY = 1  # --strict and a quality threshold broken


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh",
        description="Mesh the CGA evolved surfaces of a scene file and export them.",
        epilog="other commands: cgamesh render | verify | check | view (see cgamesh COMMAND --help)",
    )
    parser.add_argument("scene", help="the YAML scene file (format version 1), or a centreline file: "
                                      f"{', '.join(centreline_suffixes())}")
    parser.add_argument("-o", "--output", required=True, action="append",
                        help=f"output file, repeatable; its extension picks the format: {', '.join(WRITERS)}")
    parser.add_argument("--report", metavar="REPORT.json",
                        help="also write the mesh-quality report (JSON) of the meshes built")
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    add_option_flags(parser)  # the table of cgamesh.options: shared with cgamesh batch
    return parser


def centreline_suffixes() -> tuple[str, ...]:
    from cgamesh.inputs.formats import InputKind, suffixes

    return suffixes(InputKind.CENTERLINES)


def run(args: argparse.Namespace) -> str:
    """Build and write every output; returns the summary lines (one per output), or the exit
    status 1 after printing them when --strict finds a quality threshold broken."""
    from cgamesh import options as table
    from cgamesh.inputs.formats import InputKind, find

    found = find(args.scene)
    if found is not None and found.kind is InputKind.CENTERLINES:  # before the scene mesher's imports
        return realdata.run(args)
    from cgamesh.export.atomic import all_or_nothing
    from cgamesh.export.options import GltfOptions, WriteOptions
    from cgamesh.export.registry import check_distinct, vertices_written, write
    from cgamesh.pipelines.scene import Resolution, mesh_scene
    from cgamesh.progress import Progress

    values = option_values(args)
    table.refuse_elsewhere(values, InputKind.SCENE, args.scene)
    outputs = [Path(o) for o in args.output]
    for output in outputs:  # refused before any meshing: unknown formats, missing folders
        writer_for(output)
        if not output.parent.is_dir():
            raise InvalidInputError(f"cannot write {output}: directory {output.parent} does not exist")
    if args.report is not None and not Path(args.report).parent.is_dir():
        raise InvalidInputError(f"cannot write {args.report}: directory {Path(args.report).parent} does not exist")
    if args.strict and args.report is None:
        raise InvalidInputError("--strict needs --report REPORT.json")
    table.refuse_exclusive(values, {InputKind.SCENE})
    check_distinct(outputs, args.report, args.scene)
    start = time.perf_counter()
    # a file of no known format is read as a scene: its reader's message then says what is wrong
    scene = (found or table_scene_format()).read(args.scene, rendering=False)  # rendering keys: render's
    with Progress(len(scene.surfaces), enabled=not args.quiet) as progress:
        meshes = mesh_scene(scene, Resolution.from_options(values), progress=progress.advance,
                            tangents=args.tangents, max_memory=args.max_memory, outputs=args.output)
    write_options = WriteOptions(scene.up, scene.meters_per_unit, scene.units, GltfOptions.from_options(values))
    with all_or_nothing():  # every output, sidecar and the report, or none of them
        written = [write(output, meshes, write_options) for output in outputs]
        failures = write_report(args.report, [mesh for mesh, _ in meshes], args.scene) if args.report else []
    seconds = time.perf_counter() - start
    triangles = sum(mesh.triangle_count for mesh, _ in meshes)
    deviations = [mesh.max_deviation for mesh, _ in meshes if mesh.max_deviation is not None]
    deviation = f", max deviation {max(deviations):.3g}" if deviations else ""
    held = [vertices_written(output, meshes) for output in outputs]  # what each file holds (USD welds)
    summary = "\n".join(
        f"{output}: {len(meshes)} surface{'s' if len(meshes) != 1 else ''}, {count} {word}, "
        f"{triangles} triangles{deviation}, {seconds:.2f} s, {size} bytes"
        for output, size, (count, word) in zip(outputs, written, held))
    if args.strict and failures:
        if not args.quiet:
            print(summary)
        print("cgamesh: quality: " + "; ".join(failures), file=sys.stderr)
        return EXIT_QUALITY
    return summary


def table_scene_format():
    """The input table's scene format (the first of its kind)."""
    from cgamesh.inputs.formats import InputKind, formats

    return next(f for f in formats() if f.kind is InputKind.SCENE)
