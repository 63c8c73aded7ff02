"""What this machine gives two threads right now: an embarrassingly parallel compute loop.

No memory traffic, no serial part, iterations split evenly: the best case for two threads. On a
shared or virtual machine its 2-thread speed-up moves within minutes (1.3x to 1.95x measured on
the 2-core VM this project is developed on), so a measured speed-up of the engine means little
without the control's figure from the same minutes. Used by ``throughput.py`` and by the summary
of ``make bench``.

Two variants of the same loop: ``prange`` as Numba schedules it (each thread gets half of the
range up front: a thread slowed by a neighbour holds up the loop), and the chunks claimed
dynamically as the engine's kernels do (mortar1d3d._schedule): its speed-up is the ceiling for
the engine's parallel parts on the machine of the moment.
"""
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # this checkout's package

from mortar1d3d._schedule import claim, new_claims, workers  # noqa: E402


@njit(cache=True)
def _item(i):
    x = 0.0
    for k in range(1500):
        x += np.sin(i * 1e-3 + k * 1e-4)
    return x


@njit(cache=True)
def _work_serial(n, out):
    for i in range(n):
        out[i] = _item(i)


@njit(parallel=True, cache=True)
def _work(n, out):
    for i in prange(n):
        out[i] = _item(i)


@njit(parallel=True, cache=True)
def _work_claimed(n, out, workers):
    claims = new_claims(n, workers)
    for worker in prange(workers):
        begin, stop = claim(claims, n, worker)
        while begin < stop:
            for i in range(begin, stop):
                out[i] = _item(i)
            begin, stop = claim(claims, n, worker)


def control_times(threads=(1, 2), size=16000, dynamic=False):
    """Wall time of the control loop per thread count (one call each, after a warm-up call).

    ``dynamic``: the variant whose chunks are claimed dynamically, as in the engine's kernels.
    """
    out = np.empty(size)
    default = numba.get_num_threads()
    work = (lambda n: _work_claimed(n, out, workers())) if dynamic else (lambda n: _work(n, out))
    work(100)
    times = {}
    try:
        for nt in threads:
            numba.set_num_threads(nt)
            t0 = time.perf_counter()
            work(size)
            times[nt] = time.perf_counter() - t0
    finally:
        numba.set_num_threads(default)
    return times


def control_speedup(rounds=3):
    """Medians over ``rounds`` of the 1-thread / 2-thread time ratio and of the 1-thread time (s).

    The 1-thread time says how fast one core was (about 0.25 s on this project's VM when it
    is not slowed down by its neighbours, up to 0.4 s when it is).
    """
    ratios, singles = [], []
    for _ in range(rounds):
        t = control_times()
        ratios.append(t[1] / t[2])
        singles.append(t[1])
    return float(np.median(ratios)), float(np.median(singles))


def core_times(size=8000):
    """Time of the control loop run serially on each CPU this process may use, pinned in turn.

    On a virtual machine the vCPUs need not be equally fast: a neighbour on the host slows one
    of them, for minutes, and which one changes. With chunks claimed dynamically, two threads
    then reach at most 1 + t_fast / t_slow. (Two equally fast vCPUs may still slow each other
    down when both are busy, e.g. hyperthreads of one host core: only the 2-thread control
    shows that.) Returns ``{cpu: seconds}`` (empty where the OS has
    no affinity calls). Only the calling thread is pinned, and only while it runs the loop.
    """
    if not hasattr(os, "sched_setaffinity"):
        return {}
    allowed = os.sched_getaffinity(0)
    out = np.empty(size)
    _work_serial(100, out)
    times = {}
    try:
        for cpu in sorted(allowed):
            os.sched_setaffinity(0, {cpu})
            t0 = time.perf_counter()
            _work_serial(size, out)
            times[cpu] = time.perf_counter() - t0
    finally:
        os.sched_setaffinity(0, allowed)
    return times
