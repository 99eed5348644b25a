"""The batch run: every input one Dask task, results collected as they finish.

Inputs whose outputs are current (manifest.py) are skipped; the others are submitted at once
(``pure=False``: a rerun means a new task; ``retries``: a task that raised unexpectedly runs
again), and their records are written to the manifest as they arrive. A failure of one
input, including its worker dying more often than allowed, is a failed record naming the
input and the reason; it never stops the others.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from cgamesh.batching.discovery import Input, discover, plan_outputs
from cgamesh.batching.job import check_options, file_sha256, one_line, run_job
from cgamesh.batching.manifest import Manifest, normalised, tool_version
from cgamesh.batching.summary import BatchSummary, InputRecord
from cgamesh.errors import InvalidInputError

# While tasks finish the manifest is rewritten at most once a second, and less often when
# rewriting it takes long (a manifest of many thousand inputs): never more than a tenth of the time.
SAVE_EVERY_SECONDS = 1.0
SAVE_SHARE = 0.1


def run_batch(inputs: str | os.PathLike | Sequence[str | os.PathLike], outdir: str | os.PathLike, *, client=None,
              formats: Sequence[str] = ("glb",), listing: str | os.PathLike | None = None, force: bool = False,
              workers: int | None = None, scheduler: str | None = None, retries: int = 2,
              memory_limit: str | int | None = "auto", progress: bool = False,
              on_record: Callable[[InputRecord], None] | None = None, job: Callable = run_job,
              **options) -> BatchSummary:
    """Mesh every input into ``outdir`` (see the package docstring); returns the summary."""
    from cgamesh.batching.cluster import distributed
    from cgamesh.export.registry import WRITERS
    from cgamesh.inputs.formats import suffixes as input_suffixes

    distributed()  # the missing extra is reported before anything else
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    if retries < 0:
        raise InvalidInputError(f"retries must be >= 0, got {retries}")
    formats = [f.strip().lstrip(".").lower() for f in formats if f.strip()]
    if not formats:
        raise InvalidInputError("no output format given; expected e.g. glb or glb,usdz")
    for fmt in formats:
        if f".{fmt}" not in WRITERS:
            raise InvalidInputError(f"unknown output format {fmt!r}; expected some of "
                                    f"{', '.join(w.lstrip('.') for w in WRITERS)}")
    check_options(options)
    options = normalised(options)
    start = time.perf_counter()
    # Absolute paths: workers on other machines do not share this process's working folder.
    outdir = Path(outdir).absolute()
    # a folder is searched for every suffix of the input table (formats are not probed there)
    planned = plan_outputs(discover(inputs, listing, input_suffixes()), outdir, formats)
    Path(outdir).mkdir(parents=True, exist_ok=True)
    manifest = Manifest(outdir)
    version = tool_version()

    records: dict[str, InputRecord] = {}
    pending: list[Input] = []
    for item in planned:
        if item.missing:
            records[item.name] = InputRecord(str(item.path), item.name, "failed", f"{item.path}: no such file")
        elif not force and manifest.is_current(item.name, item.path, item.outputs, options, version,
                                               lambda item=item: file_sha256(item.path)):
            entry = manifest.entries[item.name]
            records[item.name] = _record(item, "skipped", entry)
        else:
            pending.append(item)

    worker_count = 0
    if pending:  # nothing to mesh: no cluster is started
        worker_count = _run_pending(pending, outdir, options, version, manifest, records, client=client,
                                    scheduler=scheduler, workers=workers, memory_limit=memory_limit,
                                    retries=retries, progress=progress, on_record=on_record, job=job)
    ordered = tuple(records[item.name] for item in planned)
    return BatchSummary(
        done=sum(r.status == "done" for r in ordered), skipped=sum(r.status == "skipped" for r in ordered),
        failed=sum(r.status == "failed" for r in ordered), seconds=time.perf_counter() - start,
        records=ordered, manifest=str(manifest.path), workers=worker_count)


def _run_pending(pending: Sequence[Input], outdir, options: dict, version: str, manifest: Manifest,
                 records: dict[str, InputRecord], *, client, scheduler, workers, memory_limit, retries, progress,
                 on_record, job) -> int:
    """Run the tasks of ``pending``, filling ``records`` and the manifest; the number of workers."""
    from cgamesh.batching.cluster import check_workers, open_client
    from cgamesh.progress import Progress

    with open_client(client, scheduler=scheduler, workers=workers, memory_limit=memory_limit,
                     retries=retries) as (active, on_cluster), \
            Progress(len(pending), enabled=progress) as bar:
        if progress and on_cluster and getattr(active, "dashboard_link", None):
            print(f"cgamesh: batch: dashboard {active.dashboard_link}", file=sys.stderr)
        worker_count = check_workers(active, version)
        last_save, save_cost = time.perf_counter(), 0.0
        try:
            for item, outcome in execute(active, pending, options, job, retries):
                entry = {"input": str(item.path.absolute()), "options": options, "tool": version,
                         "outputs": [Path(o).relative_to(outdir).as_posix() for o in item.outputs], **outcome}
                entry.pop("worker", None)
                manifest.record(item.name, entry)
                record = _record(item, outcome["status"], outcome)
                records[item.name] = record
                bar.advance(item.name)
                if on_record is not None:
                    on_record(record)
                if time.perf_counter() - last_save >= SAVE_EVERY_SECONDS:
                    manifest.save()
                    last_save, save_cost = time.perf_counter(), 0.0
        finally:
            manifest.save()
    return worker_count


def execute(client, pending: Sequence[Input], options: dict, job: Callable = run_job, retries: int = 2):
    """Submit one task per input and yield ``(input, outcome dict)`` as each finishes; a task
    that raised (after its retries) or whose worker died too often yields a failed outcome."""
    from cgamesh.batching.cluster import distributed

    as_completed = distributed().as_completed
    futures = {client.submit(job, str(item.path.absolute()), [str(o) for o in item.outputs], options,
                             pure=False, retries=retries, key=f"cgamesh-batch-{index}-{item.name}"): item
               for index, item in enumerate(pending)}
    for future in as_completed(futures):
        item = futures.pop(future)
        try:
            # a finished result held only by a worker that died since is "lost", not failed: the
            # scheduler computes it again, and result() waits for that
            outcome = future.result()
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException as error:  # raised after its retries, its worker died, or cancelled
            outcome = {"status": "failed", "reason": _task_failure(error), "sha256": "", "seconds": 0.0,
                       "vertices": 0, "bytes": 0}
        future.release()
        yield item, outcome


def _task_failure(error: BaseException) -> str:
    """One line saying why a task produced no result."""
    if type(error).__name__ == "KilledWorker":
        return ("its worker process died each time it meshed this input (memory limit exceeded, or "
                "killed); see the workers' logs")
    return one_line(f"{type(error).__name__}: {error}")


def _record(item: Input, status: str, outcome: dict) -> InputRecord:
    # the task saw the absolute path; the user is shown the path as given
    reason = outcome.get("reason", "").replace(str(item.path.absolute()), str(item.path))
    return InputRecord(
        input=str(item.path), name=item.name, status=status, reason=reason,
        outputs=tuple(str(o) for o in item.outputs), sha256=outcome.get("sha256", ""),
        seconds=float(outcome.get("seconds", 0.0)), cpu_seconds=float(outcome.get("cpu_seconds", 0.0)), vertices=int(outcome.get("vertices", 0)),
        bytes=int(outcome.get("bytes", 0)))
