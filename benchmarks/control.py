"""What this machine gives two threads right now: an embarrassingly parallel compute loop.

No memory traffic, no serial part, iterations split evenly: the best case for two threads. On a
shared or virtual machine its 2-thread speed-up moves within minutes (1.3x to 1.95x measured on
the 2-core VM this project is developed on), so a measured speed-up of the engine means little
without the control's figure from the same minutes. Used by ``throughput.py`` and by the summary
of ``make bench``.
"""
import time

import numba
import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True)
def _work(n, out):
    for i in prange(n):
        x = 0.0
        for k in range(1500):
            x += np.sin(i * 1e-3 + k * 1e-4)
        out[i] = x


def control_times(threads=(1, 2), size=16000):
    """Wall time of the control loop per thread count (one call each, after a warm-up call)."""
    out = np.empty(size)
    default = numba.get_num_threads()
    _work(100, out)
    times = {}
    try:
        for nt in threads:
            numba.set_num_threads(nt)
            t0 = time.perf_counter()
            _work(size, out)
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
