"""Linear solve of the penalty system of ``fibre_cube(n, 1000, 20)``: AMG+CG against direct.

    python benchmarks/penalty_solve.py --n 20 40 [--direct 20] [--penalty-factor 1e3]

The system is the linearised model (solid: linear elastic E = 1e9, ν = 0.3, clamped at x = 0,
traction on x = 1; 1000 torsion-free fibres E = 2e11, radius 3 mm; mortar penalty ε =
factor · E_solid), Dirichlet DOFs eliminated. Prints unknowns, assembly time, AMG setup and solve
time, CG iterations, and the direct (SuperLU) time where asked.
"""
import argparse
import time

import numpy as np

import mortar1d3d as m13
from mortar1d3d.model import Model
from mortar1d3d.solvers.linear import solve_linear


def system(n, penalty_factor):
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
    parser.add_argument("--penalty-factor", type=float, default=1e3)
    args = parser.parse_args(argv)
    print(f"{'n':>4} {'unknowns':>9} {'assembly s':>10} {'AMG setup s':>11} {'AMG solve s':>11} {'CG its':>6} "
          f"{'rel. res':>9} {'direct s':>9} {'|x_amg-x_dir|':>13}")
    for n in args.n:
        model, A, b, t_asm = system(n, args.penalty_factor)
        R = model.rigid_body_modes()[model.free]
        x, info = solve_linear(A, b, method="amg", near_nullspace=R, block_size=3, rtol=1e-8, maxiter=1000)
        direct, diff = "", ""
        if n in args.direct:
            t0 = time.perf_counter()
            xd, _ = solve_linear(A, b, method="direct")
            direct = f"{time.perf_counter() - t0:9.1f}"
            diff = f"{np.linalg.norm(x - xd) / np.linalg.norm(xd):13.2e}"
        print(f"{n:4d} {len(b):9d} {t_asm:10.1f} {info['setup_time']:11.1f} {info['solve_time']:11.1f} "
              f"{info['iterations']:6d} {info['residual']:9.1e} {direct:>9} {diff:>13}", flush=True)


if __name__ == "__main__":
    main()
