"""Batch meshing of whole datasets on Dask: ``cgamesh batch`` and ``cgamesh.batch(...)``.

    import cgamesh
    summary = cgamesh.batch(["neurons/", "more/*.yaml"], "meshes/", formats=["glb", "usdz"], around=16)
    summary.done, summary.failed, summary.failures      # counts; records of the failed inputs

Each input is one Dask task (job.py) on the caller's ``client``, an existing scheduler
(``scheduler=`` or DASK_SCHEDULER_ADDRESS) or a cluster on this machine made for the run
(cluster.py); inputs are found and their outputs named by discovery.py; a manifest in the
output folder (manifest.py) makes reruns skip what is already done; engine.py runs it all and
returns the summary (summary.py). Dask is imported only when a batch runs: it is the optional
extra ``cgamesh[batch]``.
"""

from __future__ import annotations


def batch(inputs, outdir, client=None, **options):
    """Mesh every input (files, folders, glob patterns) into ``outdir``; returns a
    :class:`~cgamesh.batching.summary.BatchSummary`.

    ``client``: a ``dask.distributed.Client`` to run on (default: ``scheduler=ADDRESS`` or
    DASK_SCHEDULER_ADDRESS, else a cluster of ``workers`` processes on this machine, one per
    core). Batch options: ``formats`` (default ``["glb"]``), ``listing`` (a file of one input
    path a line), ``force``, ``workers``, ``scheduler``, ``retries`` (default 2),
    ``memory_limit`` (per worker, default ``"auto"``: the machine's memory shared out),
    ``progress``, ``on_record`` (called with each input's record as it finishes). Every other
    keyword is a meshing option of the single-file command, from the table in cgamesh.options
    (``around``, ``along``, ``tolerance``, ``radius``, ``caps``, ``quantize``, ...); each input
    takes those that concern its kind.
    """
    from cgamesh.batching.engine import run_batch

    return run_batch(inputs, outdir, client=client, **options)
