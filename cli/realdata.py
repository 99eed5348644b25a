"""``cgamesh neuron.swc -o neuron.glb``, ``cgamesh bundle.trk -o bundle.glb --radius 0.25``: real-data inputs.

The build command (cli/build.py) hands inputs whose extension names a centreline format
(.swc, .trk, .tck, .trx, .npz) to ``run`` here; these options are added to its parser. A chain
that cannot be meshed is skipped with one line on stderr and exit status 3 (``--keep-going``,
the default), or stops the run with status 2 and nothing written (``--strict``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh_cli.arguments import positive_number, whole_number

EXIT_SKIPPED = 3
UNITS = ("nm", "um", "mm", "cm", "m")
REAL_DATA_OPTIONS = ("radius", "min_radius", "units", "up", "subdivide", "color_by", "split", "watertight",
                     "keep_going")


def add_arguments(parser: argparse.ArgumentParser) -> tuple[str, ...]:
    """The options of centreline inputs, in a group of their own; their names (argparse dests)."""
    group = parser.add_argument_group("centreline inputs (.swc, .trk, .tck, .trx, .npz)")
    group.add_argument("--radius", type=positive_number, help="a constant tube radius (required where the file has none)")
    group.add_argument("--min-radius", type=positive_number, help="raise smaller radii (and radius 0) to this")
    group.add_argument("--units", choices=UNITS, help="the file's length unit (default: SWC um, trk/tck/trx mm, npz m)")
    group.add_argument("--up", choices=("x", "y", "z"), help="which axis of the file points up (default z)")
    group.add_argument("--subdivide", type=whole_number(0), help="rings between consecutive nodes (default 3)")
    group.add_argument("--color-by", metavar="none|radius|direction|segment|SCALAR",
                       help="vertex colours: by radius, |tangent| RGB, segment, or a per-point field of the file")
    group.add_argument("--split", action="store_true", help="one mesh per segment / streamline instead of one mesh")
    group.add_argument("--watertight", action="store_true",
                       help="one closed 2-manifold surface (capped tubes, junctions and soma united)")
    group.add_argument("--keep-going", action="store_true",
                       help="skip segments that cannot be meshed, exit 3 (the default; --strict stops instead)")
    return REAL_DATA_OPTIONS


def is_real_data(path: str) -> bool:
    from cgamesh.inputs.centerlines import is_centerline_file

    return is_centerline_file(path)


def reject_for_scene(args: argparse.Namespace) -> None:
    """A scene file with an option of centreline inputs is a mistake worth one line."""
    given = [name for name in REAL_DATA_OPTIONS if getattr(args, name, None) not in (None, False)]
    if given:
        option = "--" + given[0].replace("_", "-")
        raise InvalidInputError(f"{option} applies to centreline inputs (.swc, .trk, .tck, .trx, .npz), "
                                f"not to the scene file {args.scene}")


def run(args: argparse.Namespace) -> str | int:
    """Read, mesh and write a centreline input; the summary, or EXIT_SKIPPED after printing it."""
    import numpy as np

    from cgamesh.pipelines.centerlines import TubeOptions, chain_count, mesh_centerlines, uses_batched_pass
    from cgamesh.export.registry import write, writer_for
    from cgamesh.inputs.centerlines import read_centerlines
    from cgamesh.progress import Progress

    outputs = [Path(o) for o in args.output]
    for output in outputs:
        writer_for(output)
        if not output.parent.is_dir():
            raise InvalidInputError(f"cannot write {output}: directory {output.parent} does not exist")
    if args.along is not None:
        raise InvalidInputError("--along applies to scene files; for centreline inputs give --subdivide K "
                                "(rings between consecutive nodes)")
    if args.keep_going and args.strict:
        raise InvalidInputError("--keep-going and --strict exclude each other")
    if args.tolerance is not None and (args.subdivide is not None or args.around is not None):
        raise InvalidInputError("--tolerance cannot be combined with --around or --subdivide")
    if args.watertight and args.split:
        raise InvalidInputError("--watertight makes one surface; it cannot be combined with --split")
    from cgamesh.budget import Budget, centerline_bytes
    from cgamesh.export.atomic import all_or_nothing
    from cgamesh.export.registry import check_distinct, vertices_written

    check_distinct(outputs, args.report, args.scene)
    start = time.perf_counter()
    lines = read_centerlines(args.scene, units=args.units)
    options = TubeOptions(radius=args.radius, min_radius=args.min_radius, up=args.up or "z",
                          around=8 if args.around is None else args.around,
                          subdivide=3 if args.subdivide is None else args.subdivide, tolerance=args.tolerance,
                          color_by=args.color_by or "none", split=args.split, watertight=args.watertight,
                          strict=args.strict)
    chains = chain_count(lines)
    if options.tolerance is None:  # the tolerance's own plan prices a tolerance run
        longest = int(np.diff(lines.offsets).max()) if lines.offsets is not None and len(lines.offsets) > 1 else None
        vertices, peak = centerline_bytes(len(lines.points), chains, options.around, options.subdivide,
                                          [o.suffix for o in outputs], tangents=args.tangents,
                                          batched=uses_batched_pass(options) and not options.split,
                                          longest_chain=longest)
        Budget.of(args.max_memory).require(peak, args.scene, f"memory for {vertices} vertices of tubes")
    # every output a plain glTF file and nothing else reading the mesh: hold it as they store it
    as_written = (all(o.suffix.lower() in (".glb", ".gltf") for o in outputs) and not args.quantize
                  and not args.tangents and not args.report)
    # under a tolerance every chain is planned (and the run priced), then meshed: two steps a chain
    steps = chains if options.tolerance is None else 2 * chains
    with Progress(steps, enabled=not args.quiet) as progress:
        built = mesh_centerlines(lines, options, progress=progress.advance, as_written=as_written,
                                 max_memory=args.max_memory, outputs=[str(o) for o in outputs])
    surfaces = [(mesh, built.material) for mesh in built.meshes]
    failures = []
    with all_or_nothing():  # every output, sidecar and the report, or none of them
        written = [write(output, surfaces, up=built.up, meters_per_unit=built.meters_per_unit,
                         source_units=built.units, tangents=args.tangents, quantize=args.quantize)
                   for output in outputs]
        if args.report:
            from cgamesh_cli.build import _write_report

            failures = _write_report(args.report, list(built.meshes), args.scene)
    seconds = time.perf_counter() - start
    triangles = sum(m.triangle_count for m in built.meshes)
    held = [vertices_written(output, surfaces) for output in outputs]  # what each file holds (USD welds)
    kind = "streamlines" if lines.offsets is not None else "segments"
    skipped = f" ({len(built.skipped)} skipped)" if built.skipped else ""
    summary = "\n".join(
        f"{output}: {built.chains} {kind}{skipped}, {len(built.meshes)} mesh{'es' if len(built.meshes) != 1 else ''}, "
        f"{count} {word}, {triangles} triangles, {seconds:.2f} s, {size} bytes"
        for output, size, (count, word) in zip(outputs, written, held))
    for line in built.skipped:
        print(f"cgamesh: skipped: {line}", file=sys.stderr)
    if failures:
        print("cgamesh: quality: " + "; ".join(failures), file=sys.stderr)
    if built.skipped or (args.strict and failures):
        if not args.quiet:
            print(summary)
        return EXIT_SKIPPED if built.skipped else 1
    return summary
