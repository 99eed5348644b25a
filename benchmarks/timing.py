"""The one timing rule of the benchmarks: the shortest time of several runs (wall time, or the
process's CPU time where other work shares the machine)."""

from __future__ import annotations

import gc
import time


def best_of(repeats: int, work, keep_previous: bool = False, clock=time.perf_counter) -> tuple[float, object]:
    """(shortest time in seconds of ``repeats`` calls of ``work()`` by ``clock``, the last result).

    By default nothing of one call is alive when the next starts: its result is dropped and
    collected before the clock starts, so each call allocates its arrays afresh, as a build
    in a fresh process does, and two candidates timed in one process do not pay for each
    other's memory. ``keep_previous`` keeps the previous result alive during each call (its
    memory is then recycled by the call after): the cheaper regime of a long-lived process
    building mesh after mesh, in which a candidate's time also depends on what ran before.
    """
    best, result = float("inf"), None
    for _ in range(repeats):
        if not keep_previous:
            result = None
            gc.collect()
        start = clock()
        result = work()
        best = min(best, clock() - start)
    return best, result


def best_wall_and_cpu(repeats: int, work) -> tuple[float, float, object]:
    """(shortest wall time, shortest CPU time of this process, last result) of ``repeats``
    calls of ``work()``, each timed as ``best_of`` times it: the CPU figure is the steadier one
    on a machine other work shares."""
    cpu = []

    def measured():
        start = time.process_time()
        result = work()
        cpu.append(time.process_time() - start)
        return result

    wall, result = best_of(repeats, measured)
    return wall, min(cpu), result
