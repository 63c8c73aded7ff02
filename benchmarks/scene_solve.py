"""The benchmark scene through the public ``solve``, every linear-solver path.

    python benchmarks/scene_solve.py [--n 20] [--fibres 1000] [--elements 20]
        [--enforcement penalty lagrange] [--load traction weight] [--rtol 1e-8 1e-12] [--direct]

``fibre_cube(n, fibres, elements)`` in a linear-elastic cube (ν = 0.3) clamped at x = 0: ``traction``
(E = 1e9, torsion-free fibres E = 2e11 with radius 1 cm, a traction on x = 1) or ``weight`` (the
trade-off report's solution monitor: E = 1, fibres E = 1000 with radius 2 cm, its own weight),
solved by ``mortar1d3d.solve`` with ``solver = "auto"`` and the iterative path (``amg`` for penalty,
``block`` for Lagrange multipliers), ``direct`` too with ``--direct``, at each ``analysis.rtol``.
One row per run: unknowns, the solver that ran, its iterations, the true relative residual,
the status (``converged``, or ``roundoff``: stalled at its round-off level), setup and solve
seconds, the wall time of the whole ``solve``, and the largest difference to the first run of
the same scene (relative to the largest unknown). A failure prints its message instead.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402


def scene(n, fibres, elements, enforcement, load, solver, rtol):
    beams, solid = m13.generate.fibre_cube(n, fibres, elements)
    if load == "traction":
        E, section, loads = 1e9, {"E": 2e11, "radius": 0.01}, [{"type": "traction", "on": "solid:x_max",
                                                                "value": [0, 0, -1e6]}]
    else:           # the solution monitor of the trade-off report (mortar1d3d.study.MonitorProblem)
        E, section, loads = 1.0, {"E": 1000.0, "radius": 0.02}, [{"type": "body", "value": [0, 0, -1.0]}]
    return m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": E, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": section}],
                     coupling={"enforcement": enforcement}, dirichlet=[{"on": "solid:x_min"}], load=loads,
                     analysis={"kinematics": "linear", "solver": solver, "rtol": rtol})


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=20)
    parser.add_argument("--fibres", type=int, default=1000)
    parser.add_argument("--elements", type=int, default=20)
    parser.add_argument("--enforcement", nargs="+", default=["penalty", "lagrange"])
    parser.add_argument("--load", nargs="+", default=["traction", "weight"], choices=["traction", "weight"])
    parser.add_argument("--rtol", nargs="+", type=float, default=[1e-8, 1e-12])
    parser.add_argument("--direct", action="store_true", help="also the direct solver (slow above ~50k unknowns)")
    args = parser.parse_args()
    print(f"fibre_cube({args.n}, {args.fibres}, {args.elements}); load average {os.getloadavg()[0]:.2f}")
    print(f"{'enforcement':<12}{'load':<10}{'rtol':>8} {'solver':<7}{'unknowns':>9} {'ran':<7}{'iter':>5}"
          f"{'residual':>10} {'status':<9}{'setup s':>8}{'solve s':>8}{'wall s':>8}{'diff':>10}")
    for enforcement in args.enforcement:
        for load in args.load:
            first = None
            for rtol in args.rtol:
                solvers = ["auto", "block" if enforcement == "lagrange" else "amg"] + (["direct"] if args.direct else [])
                for solver in solvers:
                    start = time.perf_counter()
                    head = f"{enforcement:<12}{load:<10}{rtol:>8.0e} {solver:<7}"
                    try:
                        result = m13.solve(scene(args.n, args.fibres, args.elements, enforcement, load, solver, rtol))
                    except Exception as error:      # report and go on with the next run
                        print(f"{head}{type(error).__name__}: {error}", flush=True)
                        continue
                    wall = time.perf_counter() - start
                    info = result.model.last_linear_info
                    first = result.z if first is None else first
                    diff = np.abs(result.z - first).max() / np.abs(first).max()
                    print(f"{head}{len(result.model.free):>9} {info['method']:<7}{info['iterations']:>5}"
                          f"{info['residual']:>10.2e} {info.get('status', 'converged'):<9}{info['setup_time']:>8.2f}"
                          f"{info['solve_time']:>8.2f}{wall:>8.1f}{diff:>10.1e}", flush=True)


if __name__ == "__main__":
    main()
