"""Cost of one Newton iteration of a Simo–Reissner beam group next to a torsion-free one on the same mesh.

    python benchmarks/simo_reissner_cost.py --elements 100 1000 [--repeat 5]

For each element count: a straight cantilever (clamped at x = 0, a tip force) meshed with that many
Hermite elements, as a ``torsion_free`` and as a ``simo_reissner`` beam (the same centreline DOFs;
the latter adds 3 rotation DOFs per mesh node and per element middle). Per model it times, after
one warm-up, the median over ``--repeat`` runs of the parts of a Newton iteration at a deformed
state (the converged state of a load step): ``residual`` (internal force + tangent, assembled in
the global layout), ``solve`` (the reduced linear solve, sparse LU for both) and ``update`` (applying the
increment: additive, or the multiplicative rotation update). It prints the unknowns, the three
times and the ratio simo_reissner / torsion_free of their sum, plus the process CPU seconds; the
1-minute load average is printed with every row (wall times on a shared machine are only
comparable at the same load).
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402
from mortar1d3d.solvers.newton import solve_load_steps  # noqa: E402


def model(kind, elements):
    section = ({"EA": 1e4, "EI": 1.0} if kind == "torsion_free" else
               {"EA": 1e4, "GA2": 1e4, "GA3": 1e4, "GI_T": 1.0, "EI2": 1.0, "EI3": 1.0})
    scene = m13.Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": elements, "model": kind,
                              "section": section}],
                      dirichlet=[{"on": "beam:0:start", "clamp": True}],
                      load=[{"type": "point", "on": "beam:0:end", "value": [0, -1.0, 0.5]}],
                      analysis={"solver": "direct"})     # the same linear solver for both
    m = Model(scene).prepare()
    z, _, _ = solve_load_steps(m, np.zeros(m.n_unknowns), 1)
    return m, z


def median_time(fn, repeat):
    fn()                                        # warm-up (compilation, caches)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def measure(kind, elements, repeat):
    m, z = model(kind, elements)
    free = m.free
    r, K = m.residual(z, 1.0)
    A, b = K[free][:, free], -r[free]
    dz = 1e-3 * np.ones(len(free))
    cpu = time.process_time()
    t_res = median_time(lambda: m.residual(z, 1.0), repeat)
    t_solve = median_time(lambda: m.solve_linear(A, b), repeat)
    t_update = median_time(lambda: m.update(z.copy(), free, dz), repeat)
    return m.n_unknowns, t_res, t_solve, t_update, time.process_time() - cpu


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(f"{'elements':>8} {'model':>14} {'unknowns':>8} {'residual s':>11} {'solve s':>9} {'update s':>9} "
          f"{'sum s':>8} {'ratio':>6} {'cpu s':>7} {'load':>5}")
    for n in args.elements:
        base = None
        for kind in ("torsion_free", "simo_reissner"):
            unknowns, t_res, t_solve, t_update, cpu = measure(kind, n, args.repeat)
            total = t_res + t_solve + t_update
            base = total if base is None else base
            print(f"{n:8d} {kind:>14} {unknowns:8d} {t_res:11.2e} {t_solve:9.2e} {t_update:9.2e} {total:8.2e} "
                  f"{total / base:6.2f} {cpu:7.2f} {os.getloadavg()[0]:5.2f}", flush=True)


if __name__ == "__main__":
    main()
