"""The one timing rule of the benchmarks: the shortest wall time of several runs."""

from __future__ import annotations

import time


def best_of(repeats: int, work) -> tuple[float, object]:
    """(shortest wall time in seconds of ``repeats`` calls of ``work()``, the last result)."""
    best, result = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        result = work()
        best = min(best, time.perf_counter() - start)
    return best, result
