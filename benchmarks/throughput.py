"""Standalone throughput of assemble_mortar outside pytest (best and median of repeated calls).

    .venv/bin/python benchmarks/throughput.py [--repeats 9] [--distort 0.1]

Same scene as the pytest-benchmark harness (fibre_cube(20, 1000, 20), n_gauss=4, straight
fibres). Every round times each integration with 1 and then 2 threads back to back, and a
control: an embarrassingly parallel compute loop (no memory traffic, no serial part) with 1 and
2 threads. The speed-up is given as the ratio of the medians and as the median of the per-round
ratios (paired: both calls of a round see the same machine state); the control's speed-up says
what this machine delivered to two threads in the same minutes. On the 2-core VM this project
is developed on, the control ranges from 1.3x to 1.95x within minutes (see benchmarks/README.md),
so a speed-up means little without it. The per-stage times are those of the fastest call.
"""
import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402

THREADS = (1, 2)


@njit(parallel=True, cache=True)
def _control(n, out):
    """Pure floating-point work, split evenly: the best case for two threads."""
    for i in prange(n):
        x = 0.0
        for k in range(1500):
            x += np.sin(i * 1e-3 + k * 1e-4)
        out[i] = x


def _timed(call):
    t0 = time.perf_counter()
    result = call()
    return time.perf_counter() - t0, result


def _speedups(times):
    one, two = np.array(times[1]), np.array(times[2])
    return np.median(one) / np.median(two), np.median(one / two)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--distort", type=float, default=0.0, metavar="A",
                        help="move the cube's interior nodes by up to A cells (generate.distort, seed 1): "
                             "no element affine, every location a Newton projection")
    args = parser.parse_args(argv)
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    if args.distort:
        solid = m13.generate.distort(solid, args.distort, seed=1)
    m13.warmup()
    out = np.empty(16000)
    _control(100, out)
    print(f"threading layer {numba.threading_layer()}, NUMBA_NUM_THREADS {numba.config.NUMBA_NUM_THREADS}"
          + (f", cube distorted by {args.distort} cells" if args.distort else ""))
    integrations = ("element", "segment")
    calls = {(i, nt): [] for i in integrations for nt in THREADS}
    control = {nt: [] for nt in THREADS}
    n_points = {}
    for _ in range(args.repeats):
        for nt in THREADS:
            numba.set_num_threads(nt)
            control[nt].append(_timed(lambda: _control(len(out), out))[0])
        for integration in integrations:
            for nt in THREADS:
                numba.set_num_threads(nt)
                t, ops = _timed(lambda: m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4))
                calls[integration, nt].append((t, ops.timings))
                n_points[integration] = ops.n_integration_points
    for integration in integrations:
        for nt in THREADS:
            runs = calls[integration, nt]
            times = np.array([t for t, _ in runs])
            best_time, best_stages = min(runs, key=lambda c: c[0])
            n = n_points[integration]
            print(f"{integration:8s} {nt} thread(s): best {best_time * 1e3:6.1f} ms = {n / best_time:.3g} GP/s, "
                  f"median {np.median(times) * 1e3:6.1f} ms = {n / np.median(times):.3g} GP/s; stages of best [ms]: "
                  + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in best_stages.items() if k != "total"))
        of_medians, paired = _speedups({nt: [t for t, _ in calls[integration, nt]] for nt in THREADS})
        print(f"{integration:8s} 2-thread speed-up: {of_medians:.2f}x (medians), {paired:.2f}x (median of paired rounds)")
    of_medians, paired = _speedups(control)
    print(f"control  1 / 2 threads median {np.median(control[1]) * 1e3:.1f} / {np.median(control[2]) * 1e3:.1f} ms: "
          f"speed-up {of_medians:.2f}x (medians), {paired:.2f}x (median of paired rounds)")


if __name__ == "__main__":
    main()
