"""Where a batch runs: a Dask client for the caller's client, an existing scheduler, or a
cluster on this machine made for the run.

Each worker runs one task at a time (one thread), so a worker's memory is that of one
single-file run; ``memory_limit`` bounds it (Dask's nanny restarts a worker that goes past it,
and the scheduler hands its task to another worker, then reports it as failed).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager

from cgamesh.optional import require

PURPOSE = "cgamesh batch"


def distributed():
    """The ``dask.distributed`` module, or the one-line error naming the ``batch`` extra."""
    require("dask", "batch", PURPOSE)
    return require("dask.distributed", "batch", PURPOSE)


def scheduler_address(scheduler: str | None) -> str | None:
    """The scheduler to use: the one given, else Dask's setting (DASK_SCHEDULER_ADDRESS), else none."""
    if scheduler:
        return scheduler
    import dask

    return dask.config.get("scheduler-address", None) or os.environ.get("DASK_SCHEDULER_ADDRESS") or None


@contextmanager
def open_client(client=None, *, scheduler: str | None = None, workers: int | None = None,
                memory_limit: str | int | None = "auto", retries: int = 2) -> Iterator[tuple[object, bool]]:
    """``(client, on_cluster)``: the caller's client, one connected to ``scheduler``, or a
    ``LocalCluster`` of ``workers`` processes (default one per core; ``workers=1`` runs in
    this process), closed again on exit."""
    dask_distributed = distributed()
    if client is not None:
        yield client, True
        return
    address = scheduler_address(scheduler)
    if address:
        from cgamesh.errors import InvalidInputError

        import dask

        try:  # Dask's connect timeout (distributed.comm.timeouts.connect, 30 s unless set)
            connected = dask_distributed.Client(address, timeout=dask.config.get("distributed.comm.timeouts.connect"))
        except (OSError, TimeoutError, ValueError) as error:  # ValueError: not an address
            raise InvalidInputError(f"cannot reach the Dask scheduler at {address}: {error}") from None
        with connected:
            yield connected, True
        return
    import dask
    from dask.utils import parse_bytes

    if isinstance(memory_limit, str) and memory_limit != "auto":
        try:
            parse_bytes(memory_limit)
        except ValueError:
            from cgamesh.errors import InvalidInputError

            raise InvalidInputError(f"memory limit {memory_limit!r}: expected a size such as 2GB or 512MiB, "
                                    "or auto") from None
    count = workers or os.cpu_count() or 1
    # A task whose worker dies is handed to another worker this many times before it is
    # reported as failed; and a worker holds only the task it runs (no queue of its own), so a
    # worker that dies takes no other input's attempt with it. Both are the scheduler's
    # settings: an existing cluster keeps its own (see the README).
    with dask.config.set({"distributed.scheduler.allowed-failures": retries,
                          "distributed.scheduler.worker-saturation": 1.0}):
        cluster = dask_distributed.LocalCluster(
            n_workers=count, threads_per_worker=1, processes=count > 1, memory_limit=memory_limit,
            dashboard_address=":0", silence_logs=logging.ERROR)
    with cluster, dask_distributed.Client(cluster) as local:
        yield local, False


def check_workers(client, version: str) -> int:
    """The number of workers, after making sure each one runs this version of cgamesh: a worker
    that cannot import the task's code would never run it, and the batch would wait forever."""
    from cgamesh.errors import InvalidInputError

    def probe():  # defined here, so that it is sent by value: it must run where cgamesh is absent
        try:
            from cgamesh.batching.manifest import tool_version
        except ImportError as error:
            return f"no cgamesh ({error})"
        return tool_version()

    answers = client.run(probe)
    if not answers:
        raise InvalidInputError(f"no Dask workers are connected to the scheduler at {client.scheduler.address}; "
                                "start some with: dask worker ADDRESS --nthreads 1")
    wrong = {address: answer for address, answer in answers.items() if answer != version}
    if wrong:
        address, answer = next(iter(wrong.items()))
        raise InvalidInputError(f"{len(wrong)} of {len(answers)} Dask workers do not run {version} (the worker at "
                                f"{address} has {answer}); install the same cgamesh, with its batch extra, on every worker")
    return len(answers)
