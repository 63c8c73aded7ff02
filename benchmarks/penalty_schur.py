"""What sets the iterations of the coupled penalty solve: CG on the solid's Schur complement
``S`` of ``fibre_cube(n, 1000, 20)``, preconditioned by the auxiliary matrix ``A_aux`` solved
exactly (SuperLU) and by its AMG V-cycle, for several penalties.

    python benchmarks/penalty_schur.py --n 20 --penalty-factor 1e2 1e3 1e4 [--smoothing 0 1 harmonic] [--drop 1e-3] [--theta 0 0.02] [--no-exact]
                                       [--inner-rtol 1e-10] [--aux-alone]

With the beam block solved exactly, the auxiliary-space sweep of ``solver = "amg"`` is CG on
``S`` preconditioned by ``A_aux``: the exact-solve column is the floor that no AMG of ``A_aux``
can go below, the V-cycle column what the solver gets (the same count as the sweep on the whole
system). ``--smoothing`` and ``--theta`` give the auxiliary space's Jacobi steps on its
prolongation and its AMG strength threshold (the other settings are the preconditioner's
defaults), ``--no-exact`` skips the SuperLU column. ``--inner-rtol R`` solves ``A_aux`` in the exact
column by an inner CG on ``A_aux`` preconditioned by its V-cycle down to the relative residual ``R``
instead of SuperLU (for n where SuperLU does not fit; 1e-10 is exact for the outer count, which
the column ``inner its`` follows with the mean inner iterations per outer one). ``--aux-alone``
adds the CG iterations on ``A_aux`` alone with its V-cycle (right-hand side: that of ``S``), the
count to hold against the solid alone's (``penalty_solve.py``'s ``solid`` row): it says how well
the AMG does on ``A_aux``, where the exact column says how well ``A_aux`` models ``S``. The scene is that of ``benchmarks/penalty_solve.py`` (same ``system``). The SuperLU
factorisation of ``A_aux`` takes about 30 s and 2 GB at n = 20; do not run it at n = 40.
"""
import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

from penalty_solve import system  # noqa: E402
from mortar1d3d.solvers.direct import factorize  # noqa: E402
from mortar1d3d.solvers.krylov import run_krylov  # noqa: E402
from mortar1d3d.solvers.preconditioners import AuxiliarySpacePreconditioner  # noqa: E402
from mortar1d3d.solvers.schur import SchurComplement  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=20)
    parser.add_argument("--penalty-factor", type=float, nargs="+", default=[1e2, 1e3, 1e4])
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--smoothing", type=lambda v: v if v == "harmonic" else int(v), nargs="+", default=[0],
                        help="Jacobi steps on the prolongation of A_aux (0: the lumped follow operator), or "
                             "'harmonic' (the beams' exact response, harmonic_prolongation)")
    parser.add_argument("--drop", type=float, default=1e-3,
                        help="relative drop threshold of the smoothed prolongation")
    parser.add_argument("--theta", type=float, nargs="+", default=[0.0],
                        help="strength threshold of the AMG of A_aux")
    parser.add_argument("--no-exact", action="store_true", help="skip the exact solve of A_aux")
    parser.add_argument("--inner-rtol", type=float, default=0.0,
                        help="solve A_aux in the exact column by CG with its V-cycle to this relative "
                             "residual instead of SuperLU (0: SuperLU)")
    parser.add_argument("--aux-alone", action="store_true",
                        help="also CG on A_aux alone with its V-cycle (how good the AMG is on A_aux)")
    args = parser.parse_args(argv)
    print(f"{'n':>3} {'eps/E':>7} {'smooth':>6} {'theta':>6} {'nnz A_aux':>10} {'its exact A_aux':>15} "
          f"{'inner its':>9} {'its V-cycle':>11} {'A_aux alone':>11} {'coarse':>7} {'factor cpu s':>12} {'load':>5}")
    for factor in args.penalty_factor:
        model, A, b, _ = system(args.n, factor)
        split = model._follow_split()
        solid = split["solid"]
        R = model.rigid_body_modes()[model.free]
        for smoothing, theta in [(k, t) for k in args.smoothing for t in args.theta]:
            pre = AuxiliarySpacePreconditioner(A, solid, split["beam"], split["prolongation"], R[solid],
                                               block_size=3, smoothing=smoothing, theta=theta, drop=args.drop,
                                               keep_auxiliary=True)
            S = SchurComplement(pre)
            operator = spla.LinearOperator(S.shape, matvec=S.matvec, dtype=float)
            rhs = S.rhs(b)

            def residual(x):
                return np.linalg.norm(rhs - S.matvec(x)) / np.linalg.norm(rhs)

            def iterations(apply, matrix=operator, right=rhs, check=residual, rtol=args.rtol):
                return run_krylov("cg", matrix, right, np.zeros(len(right)), apply, rtol, 2000, check,
                                  lambda x: 0.0)[1]

            # the column "factor cpu s": the factorisation of A_aux alone, not the CG run that uses it
            exact, inner, cpu, calls = "", "", 0.0, []
            aux = pre.auxiliary
            if not args.no_exact and args.inner_rtol > 0:
                def aux_solve(r):       # an inner CG on A_aux, its V-cycle as preconditioner
                    x, its, _, _ = run_krylov("cg", aux, r, np.zeros(len(r)), pre._cycle.matvec, args.inner_rtol,
                                              2000, lambda x: np.linalg.norm(r - aux @ x) / np.linalg.norm(r),
                                              lambda x: 0.0)
                    calls.append(its)
                    return x
                exact = iterations(aux_solve)
                inner = f"{np.mean(calls):.1f}"
            elif not args.no_exact:
                cpu = time.process_time()
                lu = factorize(aux, symmetric_positive=True)
                cpu = time.process_time() - cpu
                exact = iterations(lu.solve)
            alone = ""
            if args.aux_alone:
                alone = iterations(pre._cycle.matvec, aux, rhs,
                                   lambda x: np.linalg.norm(rhs - aux @ x) / np.linalg.norm(rhs))
            print(f"{args.n:3d} {factor:7.0e} {smoothing!s:>6} {theta:6.3f} {pre.auxiliary_nnz:10d} {exact:>15} "
                  f"{inner:>9} {iterations(pre._cycle.matvec):11d} {alone:>11} {pre.amg.levels[-1].A.shape[0]:7d} "
                  f"{cpu:12.1f} {os.getloadavg()[0]:5.1f}", flush=True)


if __name__ == "__main__":
    main()
