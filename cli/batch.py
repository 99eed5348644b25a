"""``cgamesh batch INPUT... -o OUTDIR [--format glb,usdz] [meshing options]``: mesh many input
files on Dask, on this machine or a cluster (cgamesh.batch). Exit status 0 when every input
succeeded, 3 when some failed, 2 for a bad command line."""

from __future__ import annotations

import argparse
import json
import sys

from cgamesh_cli.arguments import add_option_flags, whole_number

EXIT_SOME_FAILED = 3
EXIT_INTERRUPTED = 130  # the shell's status for Ctrl-C


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cgamesh batch",
        description="Mesh many input files, each one Dask task, on this machine or a Dask cluster. Outputs keep "
                    "the inputs' paths relative to their common folder; a manifest in OUTDIR makes a rerun "
                    "skip the inputs already done.")
    parser.add_argument("inputs", nargs="*", metavar="INPUT", help="input files, folders (searched recursively) or glob patterns")
    parser.add_argument("-o", "--outdir", required=True, metavar="OUTDIR", help="output folder (created if missing)")
    parser.add_argument("--format", default="glb", metavar="FORMATS",
                        help="output formats, comma-separated extensions (default glb), e.g. glb,usdz")
    parser.add_argument("--manifest", metavar="FILE", dest="listing",
                        help="a file of input paths, one a line (relative to its folder)")
    parser.add_argument("--workers", type=whole_number(1),
                        help="worker processes on this machine (default one per core; 1 runs in this process)")
    parser.add_argument("--scheduler", metavar="tcp://HOST:8786",
                        help="run on an existing Dask cluster (default: DASK_SCHEDULER_ADDRESS if set)")
    parser.add_argument("--retries", type=whole_number(0), default=2,
                        help="times a failed task is run again, and a task whose worker died is handed to another (default 2)")
    parser.add_argument("--memory-limit", default="auto", metavar="SIZE",
                        help="memory of each local worker, e.g. 2GB (default: the machine's memory shared out)")
    parser.add_argument("--force", action="store_true", help="mesh every input again, even those already done")
    parser.add_argument("--json", action="store_true", help="print the summary with every input's record as JSON")
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing but the failures")
    parser.meshing_options = add_option_flags(parser)  # the table of cgamesh.options, as the single-file command
    return parser


def run(args: argparse.Namespace):
    from cgamesh.batching.engine import run_batch
    from cgamesh.errors import InvalidInputError

    if not args.inputs and not args.listing:
        raise InvalidInputError("batch: no inputs; give files, folders, glob patterns or --manifest FILE")
    options = {name: getattr(args, name) for name in build_parser().meshing_options}
    try:
        summary = run_batch(args.inputs, args.outdir, formats=args.format.split(","), listing=args.listing,
                            force=args.force, workers=args.workers, scheduler=args.scheduler, retries=args.retries,
                            memory_limit=args.memory_limit, progress=not (args.quiet or args.json), **options)
    except KeyboardInterrupt:
        print("cgamesh: batch: interrupted; the manifest records the inputs that finished, and the same "
              "command continues from there", file=sys.stderr)
        return EXIT_INTERRUPTED
    for record in summary.failures:
        reason = record.reason if record.reason.startswith(record.input) else f"{record.input}: {record.reason}"
        print(f"cgamesh: batch: failed: {reason}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary.to_dict(), indent=1))
    elif not args.quiet:
        print(summary.line())
    return 0 if summary.ok else EXIT_SOME_FAILED
