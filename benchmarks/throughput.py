"""Standalone throughput of assemble_mortar outside pytest (best and median of repeated calls).

    .venv/bin/python benchmarks/throughput.py [--repeats 9] [--threads 1 2] [--distort 0.1]

Same scene as the pytest-benchmark harness (fibre_cube(20, 1000, 20), n_gauss=4, straight
fibres). Thread counts are interleaved so that both see the same machine state; the per-stage
times are those of the fastest call. Kept beside the harness because the two disagree by up to
2x on this machine (see the note on issue 2): comparing them is the first step to explain it.
"""
import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--distort", type=float, default=0.0, metavar="A",
                        help="move the cube's interior nodes by up to A cells (generate.distort, seed 1): "
                             "no element affine, every location a Newton projection")
    args = parser.parse_args(argv)
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    if args.distort:
        solid = m13.generate.distort(solid, args.distort, seed=1)
    m13.warmup()
    print(f"threading layer {numba.threading_layer()}, NUMBA_NUM_THREADS {numba.config.NUMBA_NUM_THREADS}")
    for integration in ("element", "segment"):
        runs = {nt: [] for nt in args.threads}
        for _ in range(args.repeats):
            for nt in args.threads:
                numba.set_num_threads(nt)
                t0 = time.perf_counter()
                ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
                runs[nt].append((time.perf_counter() - t0, ops.timings))
        for nt, calls in runs.items():
            times = np.array([t for t, _ in calls])
            best_time, best_stages = min(calls, key=lambda c: c[0])
            n = ops.n_integration_points
            print(f"{integration:8s} {nt} thread(s): best {best_time * 1e3:6.1f} ms = {n / best_time:.3g} GP/s, "
                  f"median {np.median(times) * 1e3:6.1f} ms = {n / np.median(times):.3g} GP/s; stages of best [ms]: "
                  + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in best_stages.items() if k != "total"))


if __name__ == "__main__":
    main()
