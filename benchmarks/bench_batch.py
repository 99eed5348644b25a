"""Batch meshing on Dask: throughput on 1 and 2 worker processes, the engine's per-task
overhead, and the machines a 25,000-neuron connectome would need to finish in an hour.

    python benchmarks/bench_batch.py [--inputs 300] [--workers 1,2] [--trivial 300]
                                     [--source FILE_OR_FOLDER ...] [--around 8 --along 32]

Inputs are copies of ``--source`` files (default: the circle and ribbon examples): scene files
are jittered (every control coordinate moved by about 1e-2) so that no two are alike, files of
any other input kind (SWC, .trk, ... once their readers exist) are copied unchanged under new
names. For each worker count a LocalCluster of that many single-threaded processes (warmed up:
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
from cgamesh_cli.main import main as cgamesh_main  # noqa: E402

DEFAULT_SOURCES = [p for p in sorted((ROOT / "examples").glob("*.yaml")) if not p.name.startswith("traced_")]
CONNECTOME = 25_000
HOUR = 3600.0


def make_inputs(sources: list[Path], count: int, folder: Path) -> list[Path]:
    """``count`` input files under ``folder`` (100 a subfolder), cycling through ``sources``."""
    rng = np.random.default_rng(7)
    made = []
    for index in range(count):
        source = sources[index % len(sources)]
        target = folder / f"part{index // 100:03d}" / f"{source.stem}_{index:05d}{source.suffix}"
        target.parent.mkdir(parents=True, exist_ok=True)
        if source.suffix.lower() in (".yaml", ".yml"):
            target.write_text(jittered(source.read_text(), rng))
        else:
            shutil.copyfile(source, target)
        made.append(target)
    return made


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
    parser.add_argument("--source", nargs="*", type=Path, help="input files or folders to copy (default: the examples)")
    parser.add_argument("--format", default="glb")
    parser.add_argument("--around", type=int, default=8)
    parser.add_argument("--along", type=int, default=32)
    parser.add_argument("--cores-per-machine", type=int, default=32, help="for the projection")
    args = parser.parse_args()
    from dask import distributed

    sources = DEFAULT_SOURCES
    if args.source:
        sources = [f for s in args.source for f in (sorted(p for p in s.rglob("*") if p.is_file()) if s.is_dir() else [s])]
    options = {"around": args.around, "along": args.along}
    counts = [int(w) for w in args.workers.split(",")]
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        inputs = make_inputs(sources, args.inputs, scratch / "inputs")
        print(f"{len(inputs)} inputs copied from {len(sources)} source files ({', '.join(sorted({s.suffix for s in sources}))}), "
              f"{args.around} x {args.along}, format {args.format}; {os.cpu_count()} cores here")
        rates, outputs, cpu, overhead = {}, {}, {}, None
        for count in counts:
            cluster = distributed.LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                                               dashboard_address=":0", silence_logs=logging.ERROR)
            with cluster, distributed.Client(cluster) as client:
                warm(client, inputs[0], scratch, args.format, options)
                start = time.perf_counter()
                summary = cgamesh.batch(scratch / "inputs", scratch / f"out{count}", client=client,
                                        formats=[args.format], **options)
                wall = time.perf_counter() - start
                assert (summary.done, summary.failed) == (len(inputs), 0), [r.reason for r in summary.failures]
                rates[count] = len(inputs) / wall
                outputs[count] = {Path(r.input): Path(r.outputs[0]) for r in summary.records}
                task_mean = sum(r.seconds for r in summary.records) / len(inputs)
                cpu[count] = sum(r.cpu_seconds for r in summary.records) / len(inputs)
                print(f"{count} worker{'s' if count > 1 else ' '}: {wall:6.2f} s, {rates[count]:7.1f} inputs/s, "
                      f"{wall / len(inputs) * 1e3:6.1f} ms per input wall; per task {task_mean * 1e3:6.1f} ms wall, "
                      f"{cpu[count] * 1e3:6.1f} ms processor; {sum(r.vertices for r in summary.records)} vertices; "
                      f"load average {os.getloadavg()[0]:.1f}")
                if count == counts[0] and args.trivial:
                    trivial = make_inputs([sources[0]], args.trivial, scratch / "trivial")
                    start = time.perf_counter()
                    result = run_batch(trivial, scratch / "trivial-out", client=client, job=trivial_job, **options)
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
        for source in inputs[:: max(1, len(inputs) // 3)]:  # and the single-file command's
            reference = scratch / "reference" / f"{source.stem}.{args.format}"
            reference.parent.mkdir(exist_ok=True)
            along = ["--along", str(args.along)] if source.suffix.lower() in (".yaml", ".yml") else []
            assert cgamesh_main([str(source), "-o", str(reference), "--around", str(args.around), *along, "-q"]) == 0
            assert first[source].read_bytes() == reference.read_bytes(), first[source]

    if len(counts) > 1 and counts[0] == 1:
        second = counts[1]
        print(f"speed-up from 1 to {second} workers: {rates[second] / rates[1]:.2f}x (target >= 1.6x for 2)")
    per_input = 1.0 / rates[counts[0]] * counts[0]  # seconds of one worker per input
    efficiency = min(1.0, rates[counts[-1]] / (rates[counts[0]] * counts[-1] / counts[0])) if len(counts) > 1 else 1.0
    machines = math.ceil(CONNECTOME * per_input / (HOUR * args.cores_per_machine * efficiency))
    print(f"projection: {CONNECTOME} inputs at {per_input * 1e3:.1f} ms per input per worker, "
          f"{efficiency:.0%} parallel efficiency, {args.cores_per_machine} cores per machine: "
          f"{machines} machine{'s' if machines != 1 else ''} to finish in an hour "
          f"({CONNECTOME * per_input / HOUR:.2f} core-hours)")
    cpu_machines = math.ceil(CONNECTOME * (cpu[counts[0]] + (overhead or 0.0)) / (HOUR * args.cores_per_machine))
    print(f"projection from processor time per task plus engine overhead (a machine of idle cores): "
          f"{cpu_machines} machine{'s' if cpu_machines != 1 else ''}")
    if os.getloadavg()[0] > (os.cpu_count() or 1) * 0.75:
        print(f"note: load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores: other processes share "
              "them, so the workers' scaling measured here is a lower bound")
    if all(s.suffix.lower() in (".yaml", ".yml") for s in sources):
        print("(these are scene files: pass --source with SWC neurons for a connectome's own per-neuron cost)")


if __name__ == "__main__":
    main()
