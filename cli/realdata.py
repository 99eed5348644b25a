"""``cgamesh neuron.swc -o neuron.glb``, ``cgamesh bundle.trk -o bundle.glb --radius 0.25``: real-data inputs.

The build command (cli/build.py) hands inputs of a centreline format of the input table
(cgamesh.inputs.formats: .swc, .trk, .tck, .trx, .npz and any registered) to ``run`` here; their
options are the table's of cgamesh.options, which build's parser has as flags. A chain
that cannot be meshed is skipped with one line on stderr and exit status 3 (``--keep-going``,
the default), or stops the run with status 2 and nothing written (``--strict``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from cgamesh.errors import InvalidInputError
from cgamesh_cli.arguments import option_values
from cgamesh_cli.report import write_report

EXIT_SKIPPED = 3


def run(args: argparse.Namespace) -> str | int:
    """Read, mesh and write a centreline input; the summary, or EXIT_SKIPPED after printing it."""
    import numpy as np

    from cgamesh import options as table
    from cgamesh.pipelines.centerlines import TubeOptions, chain_count, mesh_centerlines, uses_batched_pass
    from cgamesh.export.options import GltfOptions, WriteOptions
    from cgamesh.export.registry import write, writer_for
    from cgamesh.inputs.formats import InputKind, read_centerlines
    from cgamesh.progress import Progress

    outputs = [Path(o) for o in args.output]
    for output in outputs:
        writer_for(output)
        if not output.parent.is_dir():
            raise InvalidInputError(f"cannot write {output}: directory {output.parent} does not exist")
    values = option_values(args)
    table.refuse_elsewhere(values, InputKind.CENTERLINES, args.scene)
    table.refuse_exclusive(values, {InputKind.CENTERLINES})
    from cgamesh.budget import Budget, centerline_bytes
    from cgamesh.export.atomic import all_or_nothing
    from cgamesh.export.registry import check_distinct, vertices_written

    check_distinct(outputs, args.report, args.scene)
    start = time.perf_counter()
    lines = read_centerlines(args.scene, units=args.units)
    options = TubeOptions.from_options(values)
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
        write_options = WriteOptions(built.up, built.meters_per_unit, built.units, GltfOptions.from_options(values))
        written = [write(output, surfaces, write_options) for output in outputs]
        if args.report:
            failures = write_report(args.report, list(built.meshes), args.scene)
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
