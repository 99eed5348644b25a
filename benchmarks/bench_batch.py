"""Batch meshing on Dask: throughput on 1 and 2 worker processes, the engine's per-task
overhead, and the machines a 25,000-neuron connectome would need to finish in an hour.

    python benchmarks/bench_batch.py [--inputs 300] [--workers 1,2] [--trivial 300]
                                     [--source FILE_OR_FOLDER ...] [--around 8 --along 32]

Inputs are jittered copies of ``--source`` files, so that no two are alike (default: the real
data that installed packages ship: navis' five hemibrain neurons (SWC), dipy's fornix of 300
streamlines and nibabel's small .trk / .tck test files; ``--source examples`` takes the circle
and ribbon scene files instead). Scene files have every control coordinate moved by about 1e-2;
SWC files every node by about 1e-3 of its radius; tractograms every streamline point by about
1e-3 mm (read and written back with nibabel, header kept). For each worker count a LocalCluster of that many single-threaded processes (warmed up:
modules imported) meshes all of them through ``cgamesh.batch`` into a fresh folder, and the
wall time gives inputs/s (target: >= 1.6x from the second worker). The overhead is the wall
time per task of ``--trivial`` tasks that do no work, through the same engine on one worker
(discovery, submission, as_completed, manifest; target < 20 ms). The projection divides the
measured single-worker cost per input into an hour of a machine's cores, scaled by the
measured efficiency of the second worker.

Checks (never times): every input done and none failed; both runs wrote byte-identical outputs;
a sample of them equals the single-file command's output.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import cgamesh  # noqa: E402
from cgamesh.batching.engine import run_batch  # noqa: E402
from cgamesh.inputs.formats import InputKind, format_of  # noqa: E402
from cgamesh_cli.main import main as cgamesh_main  # noqa: E402

EXAMPLES = [p for p in sorted((ROOT / "examples").glob("*.yaml")) if not p.name.startswith("traced_")]
CONNECTOME = 25_000
HOUR = 3600.0


def make_inputs(sources: list[Path], count: int, folder: Path) -> list[Path]:
    """``count`` input files under ``folder`` (100 a subfolder), cycling through ``sources``."""
    rng = np.random.default_rng(7)
    made = []
    for index in range(count):
        source = sources[index % len(sources)]
        target = folder / kind_of(source) / f"part{index // 100:03d}" / f"{source.stem}_{index:05d}{source.suffix}"
        target.parent.mkdir(parents=True, exist_ok=True)
        suffix = source.suffix.lower()
        if suffix in (".yaml", ".yml"):
            target.write_text(jittered(source.read_text(), rng))
        elif suffix == ".swc":
            target.write_text(jittered_swc(source.read_text(), rng))
        elif suffix in (".trk", ".tck"):
            jittered_tractogram(source, target, rng)
        else:
            shutil.copyfile(source, target)
        made.append(target)
    return made


def kind_of(path: Path) -> str:
    if format_of(path).kind is InputKind.SCENE:
        return "scene"
    return "neuron" if path.suffix.lower() == ".swc" else "tractogram"


def options_for(kind: str, args: argparse.Namespace) -> dict:
    """The options a user gives a batch of one kind: scene files take the resolution along their
    surfaces, neurons keep their own radii, tractograms (which carry none) need a radius."""
    options = {"around": args.around}
    if kind == "scene":
        options["along"] = args.along
    elif kind == "tractogram":
        options["radius"] = args.radius
    return options


def as_command_line(options: dict) -> list[str]:
    return [a for key, value in options.items() for a in (f"--{key}", str(value))]


def real_data_sources() -> list[Path]:
    """The real centreline files installed packages ship (see tests/realdata_files.py)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from realdata_files import fornix, neurons, nibabel_file

    swc = neurons()
    small = [nibabel_file(name) for name in ("standard.trk", "standard.tck", "complex.trk")]
    # interleaved, so that any count of inputs from six up has every kind
    return [fornix(), small[0], swc[0], small[1], swc[1], small[2], *swc[2:]]


def jittered_swc(text: str, rng: np.random.Generator) -> str:
    """Every node moved by about 1e-3 of its radius; comments, ids, types, radii and parents kept."""
    lines = []
    for line in text.splitlines():
        fields = line.split()
        if line.lstrip().startswith("#") or len(fields) < 7:
            lines.append(line)
            continue
        radius = abs(float(fields[5])) or 1.0
        moved = [float(v) + float(rng.normal(0.0, 1e-3 * radius)) for v in fields[2:5]]
        lines.append(" ".join([*fields[:2], *(repr(v) for v in moved), *fields[5:]]))
    return "\n".join(lines) + "\n"


def jittered_tractogram(source: Path, target: Path, rng: np.random.Generator) -> None:
    """Every streamline point moved by about 1e-3 mm, in the file's own format and header."""
    import nibabel as nib

    tractogram_file = nib.streamlines.load(str(source))
    tractogram = tractogram_file.tractogram
    streamlines = nib.streamlines.ArraySequence(
        [s + rng.normal(0.0, 1e-3, s.shape).astype(s.dtype) for s in tractogram.streamlines])
    moved = nib.streamlines.Tractogram(streamlines, affine_to_rasmm=np.eye(4))
    nib.streamlines.save(type(tractogram_file)(moved, header=tractogram_file.header), str(target))


def jittered(text: str, rng: np.random.Generator) -> str:
    document = yaml.safe_load(text)

    def move(value):
        if isinstance(value, list) and value and all(isinstance(v, (int, float)) for v in value):
            return [float(v) + float(rng.normal(0.0, 1e-2)) for v in value]
        if isinstance(value, list):
            return [move(v) for v in value]
        if isinstance(value, dict):
            return {k: (v if k == "normal" else move(v)) for k, v in value.items()}
        return value

    for surface in document["surfaces"]:
        surface["controls"] = move(surface["controls"])
    return yaml.safe_dump(document, sort_keys=False)


def trivial_job(source, outputs, options):
    """A task that does no work: what the engine costs on its own."""
    return {"status": "done", "reason": "", "sha256": "", "seconds": 0.0, "vertices": 0, "bytes": 0}


def bare_dask(client, inputs: list[Path]) -> float:
    """Seconds for the same trivial tasks through Dask alone (submit, as_completed, result):
    the baseline of the engine's overhead, measured in the same run."""
    from dask.distributed import as_completed

    start = time.perf_counter()
    futures = [client.submit(trivial_job, str(path), [], {}, pure=False, retries=2) for path in inputs]
    for future in as_completed(futures):
        assert future.result()["status"] == "done"
    return time.perf_counter() - start


def warm(client, source: Path, folder: Path, fmt: str, options: dict) -> None:
    """Mesh one input in every worker first (modules imported, caches filled), as a long batch
    has after its first inputs, so that the start-up is not counted as throughput."""
    from cgamesh.batching.job import run_job

    def mesh_once():
        output = folder / f"warm-{os.getpid()}.{fmt}"
        return run_job(str(source), [str(output)], options)["status"]
    assert set(client.run(mesh_once).values()) == {"done"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--inputs", type=int, default=300)
    parser.add_argument("--workers", default="1,2", help="worker counts to measure, comma-separated")
    parser.add_argument("--trivial", type=int, default=300, help="trivial tasks for the overhead")
    parser.add_argument("--source", nargs="*", type=Path,
                        help="input files or folders to copy, or the word 'examples' (default: the shipped real data)")
    parser.add_argument("--format", default="glb")
    parser.add_argument("--around", type=int, default=8)
    parser.add_argument("--along", type=int, default=32)
    parser.add_argument("--radius", type=float, default=0.5,
                        help="tube radius of tractograms, which carry none (scene files and SWC keep theirs)")
    parser.add_argument("--cores-per-machine", type=int, default=32, help="for the projection")
    args = parser.parse_args()
    from dask import distributed

    sources = real_data_sources()
    if args.source == [Path("examples")]:
        sources = EXAMPLES
    elif args.source:
        sources = [f for s in args.source for f in (sorted(p for p in s.rglob("*") if p.is_file()) if s.is_dir() else [s])]
    counts = [int(w) for w in args.workers.split(",")]
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        inputs = make_inputs(sources, args.inputs, scratch / "inputs")
        kinds = sorted({kind_of(path) for path in inputs})
        print(f"{len(inputs)} inputs copied from {len(sources)} source files ({', '.join(sorted({s.suffix for s in sources}))}), "
              f"{args.around} around ({args.along} along scene files, radius {args.radius} for tractograms), "
              f"format {args.format}; one batch per kind ({', '.join(kinds)}); {os.cpu_count()} cores here")
        rates, outputs, overhead, per_kind = {}, {}, None, {}
        for count in counts:
            cluster = distributed.LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                                               dashboard_address=":0", silence_logs=logging.ERROR)
            with cluster, distributed.Client(cluster) as client:
                walls, records = {}, []
                for kind in kinds:
                    options = options_for(kind, args)
                    warm(client, next(p for p in inputs if kind_of(p) == kind), scratch, args.format, options)
                    start = time.perf_counter()
                    summary = cgamesh.batch(scratch / "inputs" / kind, scratch / f"out{count}" / kind, client=client,
                                            formats=[args.format], **options)
                    walls[kind] = time.perf_counter() - start
                    assert summary.failed == 0, [r.reason for r in summary.failures]
                    records += summary.records
                    done = summary.done
                    print(f"{count} worker{'s' if count > 1 else ''}, {done:4d} {kind + 's':<11}: {walls[kind]:7.2f} s, "
                          f"{done / walls[kind]:6.2f} inputs/s; per task "
                          f"{sum(r.seconds for r in summary.records) / done * 1e3:7.1f} ms wall, "
                          f"{sum(r.cpu_seconds for r in summary.records) / done * 1e3:7.1f} ms processor")
                    if count == counts[0]:
                        per_kind[kind] = (sum(r.seconds for r in summary.records) / done,
                                          sum(r.cpu_seconds for r in summary.records) / done, done)
                assert len(records) == len(inputs)
                wall = sum(walls.values())
                rates[count] = len(inputs) / wall
                outputs[count] = {Path(r.input): Path(r.outputs[0]) for r in records}
                print(f"{count} worker{'s' if count > 1 else ''}, all {len(inputs)} inputs: {wall:6.2f} s, "
                      f"{rates[count]:6.2f} inputs/s; {sum(r.vertices for r in records)} vertices; "
                      f"load average {os.getloadavg()[0]:.1f}")
                if count == counts[0] and args.trivial:
                    trivial = make_inputs([sources[0]], args.trivial, scratch / "trivial")
                    start = time.perf_counter()
                    result = run_batch(trivial, scratch / "trivial-out", client=client, job=trivial_job)
                    wall = time.perf_counter() - start
                    assert result.done == len(trivial)
                    overhead = wall / len(trivial)
                    bare = bare_dask(client, trivial) / len(trivial)
                    print(f"per-task overhead of the engine on {count} worker{'s' if count > 1 else ''}: "
                          f"{overhead * 1e3:.2f} ms ({len(trivial)} trivial tasks; target < 20 ms); bare Dask "
                          f"submit + as_completed of the same tasks: {bare * 1e3:.2f} ms, ratio {overhead / bare:.2f}")

        first = outputs[counts[0]]
        for count in counts[1:]:  # the same outputs whatever the number of workers
            for source, path in first.items():
                assert path.read_bytes() == outputs[count][source].read_bytes(), path
        for kind in kinds:  # and the single-file command's, on a sample of each kind
            sample = [p for p in inputs if kind_of(p) == kind]
            for source in sample[:: max(1, len(sample) // 2)]:
                reference = scratch / "reference" / f"{source.stem}.{args.format}"
                reference.parent.mkdir(exist_ok=True)
                command = [str(source), "-o", str(reference), *as_command_line(options_for(kind, args)), "-q"]
                assert cgamesh_main(command) == 0
                assert first[source].read_bytes() == reference.read_bytes(), first[source]

    if len(counts) > 1 and counts[0] == 1:
        second = counts[1]
        print(f"speed-up from 1 to {second} workers: {rates[second] / rates[1]:.2f}x (target >= 1.6x for 2)")
    efficiency = min(1.0, rates[counts[-1]] / (rates[counts[0]] * counts[-1] / counts[0])) if len(counts) > 1 else 1.0
    # a connectome is neurons: project from the neurons' own cost when there are any
    kind = "neuron" if "neuron" in per_kind else None
    per_input = per_kind[kind][0] + (overhead or 0.0) if kind else 1.0 / rates[counts[0]] * counts[0]
    what = "neurons" if kind else "inputs"
    machines = math.ceil(CONNECTOME * per_input / (HOUR * args.cores_per_machine * efficiency))
    print(f"projection: {CONNECTOME} {what} at {per_input * 1e3:.1f} ms per {what[:-1]} per worker "
          f"(task wall time plus engine overhead), {efficiency:.0%} parallel efficiency, {args.cores_per_machine} "
          f"cores per machine: {machines} machine{'s' if machines != 1 else ''} to finish in an hour "
          f"({CONNECTOME * per_input / HOUR:.2f} core-hours)")
    if os.getloadavg()[0] > (os.cpu_count() or 1) * 0.75:
        print(f"note: load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores: other processes share "
              "them, so the workers' scaling measured here is a lower bound")
    if all(s.suffix.lower() in (".yaml", ".yml") for s in sources):
        print("(these are scene files: the default sources, real neurons among them, give a connectome's own per-neuron cost)")


if __name__ == "__main__":
    main()
