"""Linear solve of the penalty system of ``fibre_cube(n, 1000, 20)``: AMG paths against direct.

    python benchmarks/penalty_solve.py --n 10 20 40 [--direct 10 20] [--plain 10] [--penalty-factor 1e3]

The system is the linearised model (solid: linear elastic E = 1e9, ν = 0.3, clamped at x = 0,
traction on x = 1; 1000 torsion-free fibres E = 2e11, radius 3 mm; mortar penalty ε =
factor · E_solid, default 1e3 as in scenes without a penalty), Dirichlet DOFs eliminated.
For every n it prints the unknowns (solid + beam), assembly time, and for each solver:
setup and solve seconds, CG iterations, the true relative residual and the difference to the
direct solution where that was computed, and the process CPU seconds of setup + solve (on a
loaded machine closer to the idle wall time than the wall time is). Solvers: ``aux`` (CG + auxiliary-space preconditioner,
what ``solver = "amg"``/``"auto"`` runs for penalty-coupled beams), ``amg`` (CG + smoothed
aggregation on the whole matrix, the path before; ``--plain``, slow at large ε) and ``direct``
(SuperLU, ``--direct``). The 1-minute load average is printed with every row: wall times on a
shared machine are only comparable at the same load.
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
from mortar1d3d.solvers.linear import solve_linear  # noqa: E402


def system(n, penalty_factor):
    """(model, A, b, assembly seconds) of the reduced linear penalty system."""
    beams, solid = m13.generate.fibre_cube(n, 1000, 20)
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                      coupling={"penalty": penalty_factor * 1e9},
                      dirichlet=[{"on": "solid:x_min"}],
                      load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                      analysis={"kinematics": "linear", "solver": "amg"})
    start = time.perf_counter()
    model = Model(scene).prepare()
    z = np.zeros(model.n_unknowns)
    r, K = model.residual(z, 1.0)
    free = model.free
    A = K[free][:, free].tocsr()
    b = -r[free]
    return model, A, b, time.perf_counter() - start


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, nargs="+", default=[20, 40])
    parser.add_argument("--direct", type=int, nargs="*", default=[20], help="sizes n to also solve directly")
    parser.add_argument("--plain", type=int, nargs="*", default=[], help="sizes n to also solve with plain AMG")
    parser.add_argument("--penalty-factor", type=float, default=1e3)
    parser.add_argument("--rtol", type=float, default=1e-8)
    args = parser.parse_args(argv)
    print(f"penalty ε = {args.penalty_factor:g} E_solid, rtol {args.rtol:g}")
    print(f"{'n':>3} {'solid':>7} {'beam':>7} {'asm s':>6} {'solver':>6} {'setup s':>8} {'solve s':>8} "
          f"{'total s':>8} {'cpu s':>7} {'its':>5} {'rel. res':>8} {'|x-x_dir|':>9} {'load':>5}")
    for n in args.n:
        model, A, b, t_asm = system(n, args.penalty_factor)
        R = model.rigid_body_modes()[model.free]
        split = model._follow_split()
        sizes = f"{n:3d} {len(split['solid']):7d} {len(split['beam']):7d} {t_asm:6.1f}"
        runs = [("aux", dict(method="aux", near_nullspace=R, block_size=3, **split))]
        if n in args.plain:
            runs.append(("amg", dict(method="amg", near_nullspace=R, block_size=3)))
        if n in args.direct:
            runs.append(("direct", dict(method="direct")))
        results = {}
        for name, kw in runs:
            cpu = time.process_time()
            x, info = solve_linear(A, b, rtol=args.rtol, maxiter=2000, **kw)
            info["cpu_time"] = time.process_time() - cpu
            info["load"] = os.getloadavg()[0]
            results[name] = (x, info)
        x_direct = results.get("direct", (None,))[0]
        for name, (x, info) in results.items():
            diff = "" if x_direct is None or name == "direct" else \
                f"{np.linalg.norm(x - x_direct) / np.linalg.norm(x_direct):9.1e}"
            total = info["setup_time"] + info["solve_time"]
            print(f"{sizes} {name:>6} {info['setup_time']:8.1f} {info['solve_time']:8.1f} {total:8.1f} "
                  f"{info['cpu_time']:7.1f} "
                  f"{info['iterations']:5d} {info['residual']:8.1e} {diff:>9} {info['load']:5.1f}", flush=True)


if __name__ == "__main__":
    main()
