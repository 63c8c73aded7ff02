"""Thread scaling of the element-based integration-point kernel against the whole call.

    NUMBA_NUM_THREADS=2 .venv/bin/python benchmarks/thread_scaling.py [--repeats 7] [--blocks 2]

Scene of the throughput benchmark (fibre_cube(20, 1000, 20), n_gauss = 4). For each block and
thread count, best and median of ``--repeats`` calls of ``element_points`` alone (search done
once beforehand), of the broad phase (``KernelInput``) and of the whole element-based
``assemble_mortar``. Repeating the blocks shows how much the machine itself drifts between
them: on a shared VM that drift can exceed the effect of a second thread.
"""
import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13                                          # noqa: E402
from mortar1d3d.geometry.context import KernelInput               # noqa: E402
from mortar1d3d.integration.points import element_points         # noqa: E402


def _times(f, repeats):
    t = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        t.append(time.perf_counter() - start)
    return 1e3 * min(t), 1e3 * float(np.median(t))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--blocks", type=int, default=2)
    args = parser.parse_args(argv)
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    m13.warmup()
    ctx = KernelInput(beams, solid)
    print(f"threading layer {numba.threading_layer()}; ms as best / median of {args.repeats}")
    for block in range(args.blocks):
        for threads in (1, 2):
            numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
            kernel = _times(lambda: element_points(ctx, 4), args.repeats)
            search = _times(lambda: KernelInput(beams, solid), args.repeats)
            whole = _times(lambda: m13.assemble_mortar(beams, solid, integration="element", n_gauss=4), args.repeats)
            print(f"block {block} {numba.get_num_threads()} thread(s): element_points {kernel[0]:6.1f} / "
                  f"{kernel[1]:6.1f}, KernelInput {search[0]:5.1f} / {search[1]:5.1f}, "
                  f"assemble_mortar {whole[0]:6.1f} / {whole[1]:6.1f}")


if __name__ == "__main__":
    main()
