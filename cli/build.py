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
from cgamesh_cli.arguments import add_budget_option, positive_number, whole_number

EXIT_QUALITY = 1  # --strict and a quality threshold broken


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh",
        description="Mesh the CGA evolved surfaces of a scene file and export them.",
        epilog="other commands: cgamesh render | verify | check | view (see cgamesh COMMAND --help)",
    )
    parser.add_argument("scene", help="the YAML scene file (format version 1), or a centreline file: "
                                      ".swc, .trk, .tck, .trx, .npz")
    parser.add_argument("-o", "--output", required=True, action="append",
                        help=f"output file, repeatable; its extension picks the format: {', '.join(WRITERS)}")
    add_meshing_options(parser)
    parser.add_argument("--report", metavar="REPORT.json",
                        help="also write the mesh-quality report (JSON) of the meshes built")
    parser.add_argument("--strict", action="store_true",
                        help="with --report: exit 1 when a quality threshold is broken; centreline inputs: "
                             "a segment that cannot be meshed stops the run (exit 2, nothing written)")
    add_budget_option(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    realdata.add_arguments(parser)
    return parser


def add_meshing_options(parser: argparse.ArgumentParser) -> tuple[str, ...]:
    """Add the options that shape each mesh to ``parser``; their names (argparse dests).

    Shared with ``cgamesh batch``, which forwards them, as a plain dict, to every input.
    """
    group = parser.add_argument_group("meshing options")
    actions = [
        group.add_argument("--around", type=whole_number(2), help="vertices around every circle, or across every ribbon (overrides the file)"),
        group.add_argument("--along", type=whole_number(2), help="rings along every surface (overrides the file)"),
        group.add_argument("--tolerance", type=positive_number,
                           help="largest distance of every mesh from its true surface, in file units "
                                "(instead of a resolution; overrides the file)"),
        group.add_argument("--tangents", action="store_true",
                           help="glTF: write a TANGENT attribute (so normal maps work)"),
        group.add_argument("--quantize", action="store_true",
                           help="glTF: store positions, normals and UVs in 16 / 8 bits (KHR_mesh_quantization)"),
    ]
    return tuple(action.dest for action in actions)


def run(args: argparse.Namespace) -> str:
    """Build and write every output; returns the summary lines (one per output), or the exit
    status 1 after printing them when --strict finds a quality threshold broken."""
    if realdata.is_real_data(args.scene):  # before the scene mesher's imports, which it does not need
        return realdata.run(args)
    from cgamesh.export.atomic import all_or_nothing
    from cgamesh.export.registry import check_distinct, vertices_written, write
    from cgamesh.pipelines.scene import Resolution, mesh_scene
    from cgamesh.progress import Progress
    from cgamesh.inputs.scene import load_scene

    realdata.reject_for_scene(args)
    outputs = [Path(o) for o in args.output]
    for output in outputs:  # refused before any meshing: unknown formats, missing folders
        writer_for(output)
        if not output.parent.is_dir():
            raise InvalidInputError(f"cannot write {output}: directory {output.parent} does not exist")
    if args.report is not None and not Path(args.report).parent.is_dir():
        raise InvalidInputError(f"cannot write {args.report}: directory {Path(args.report).parent} does not exist")
    if args.strict and args.report is None:
        raise InvalidInputError("--strict needs --report REPORT.json")
    if args.tolerance is not None and (args.around is not None or args.along is not None):
        raise InvalidInputError("--tolerance cannot be combined with --around or --along")
    check_distinct(outputs, args.report, args.scene)
    start = time.perf_counter()
    scene = load_scene(args.scene, rendering=False)  # the rendering keys are render's and verify's
    with Progress(len(scene.surfaces), enabled=not args.quiet) as progress:
        meshes = mesh_scene(scene, Resolution(args.around, args.along, args.tolerance), progress=progress.advance,
                            tangents=args.tangents, max_memory=args.max_memory, outputs=args.output)
    with all_or_nothing():  # every output, sidecar and the report, or none of them
        written = [write(output, meshes, up=scene.up, meters_per_unit=scene.meters_per_unit, source_units=scene.units,
                         tangents=args.tangents, quantize=args.quantize) for output in outputs]
        failures = _write_report(args.report, [mesh for mesh, _ in meshes], args.scene) if args.report else []
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


def _write_report(path: str, meshes, source: str) -> list[str]:
    """Write the quality report of ``meshes`` as JSON at ``path`` (atomically); its failures."""
    from cgamesh.export.atomic import atomic_write
    from cgamesh.quality import report

    result = report(meshes, str(source))
    with atomic_write(path) as f:
        f.write(result.to_json().encode() + b"\n")
    return result.failures()
