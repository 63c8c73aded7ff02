"""How well the auxiliary matrix ``A_aux = Eᵀ A E`` (``E = [I; P]``) models the solid's Schur
complement ``S = A_SS − A_SB A_BB⁻¹ A_BS`` of the penalty system of ``fibre_cube(n, 1000, 20)``:
the spectrum of ``A_aux⁻¹ S`` (dense, small n), for the lumped follow operator and for it smoothed
towards the beams' response ``−A_BB⁻¹ A_BS`` (:func:`~mortar1d3d.solvers.preconditioners.smooth_prolongation`).

    python benchmarks/penalty_spectrum.py --n 6 --penalty-factor 1e2 1e3 1e4

``A_aux − S = eᵀ A_BB e`` with ``e = P + A_BB⁻¹ A_BS`` (the defect of ``P`` against the beams'
response), so the eigenvalues lie in (0, 1] and CG on ``S`` preconditioned by an exact solve of
``A_aux`` needs about ``√(1/λ_min)`` times a constant iterations. For the eigenvector ``v`` of
``λ_min`` the script splits the defect energy ``(e v)ᵀ A_BB (e v)`` into the beams' own stiffness
``K_BB`` and the penalty term ``ε Dᵀκ⁻¹D`` (``K_BB`` from the same scene assembled at two penalties:
``A_BB`` is affine in ε). ``S`` is formed densely (banded solves with the solid's columns in chunks of
200): about 15 s at n = 6, minutes and gigabytes from n = 10 on.
"""
import argparse
import os
import sys
from pathlib import Path

import numpy as np
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

from penalty_solve import system  # noqa: E402
from mortar1d3d.solvers.direct import factorize_spd_block  # noqa: E402
from mortar1d3d.solvers.preconditioners import smooth_prolongation  # noqa: E402


def blocks(n, factor):
    model, A, _, _ = system(n, factor)
    split = model._follow_split()
    s, b = split["solid"], split["beam"]
    rows = A[b].tocsr()
    return A[s][:, s].toarray(), rows[:, s].tocsr(), rows[:, b].tocsr(), split["prolongation"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=6)
    parser.add_argument("--penalty-factor", type=float, nargs="+", default=[1e2, 1e3, 1e4])
    parser.add_argument("--variants", nargs="+", default=["0:0", "1:0", "1:1e-3", "2:0"], metavar="STEPS:DROP",
                        help="Jacobi steps on the lumped follow operator and the relative drop threshold")
    args = parser.parse_args(argv)
    print(f"{'n':>3} {'eps/E':>7} {'steps':>5} {'drop':>6} {'nnz P':>9} {'lam_min':>8} {'lam_max':>8} "
          f"{'cond':>7} {'penalty share':>13} {'load':>5}")
    for factor in args.penalty_factor:
        A_ss, A_bs, A_bb, P0 = blocks(args.n, factor)
        K_bb = 2 * A_bb - blocks(args.n, 2 * factor)[2]        # A_BB = K_BB + ε G: the beams' own part
        factor_bb = factorize_spd_block(A_bb)
        response = np.empty((A_bb.shape[0], A_ss.shape[0]))   # −A_BB⁻¹ A_BS, column chunks
        for c in range(0, A_ss.shape[0], 200):
            response[:, c:c + 200] = factor_bb.solve(-A_bs[:, c:c + 200].toarray())
        S = A_ss + A_bs.T @ response
        S = 0.5 * (S + S.T)
        for variant in args.variants:
            steps, drop = int(variant.split(":")[0]), float(variant.split(":")[1])
            P = smooth_prolongation(A_bb, A_bs, P0, steps, drop)
            cross = (A_bs.T @ P).toarray()
            aux = A_ss + cross + cross.T + (P.T @ (A_bb @ P)).toarray()
            lam, V = scipy.linalg.eigh(S, aux)
            e = P @ V[:, 0] - response @ V[:, 0]
            total = e @ (A_bb @ e)
            share = (total - e @ (K_bb @ e)) / total
            print(f"{args.n:3d} {factor:7.0e} {steps:5d} {drop:6.0e} {P.nnz:9d} {lam[0]:8.4f} {lam[-1]:8.4f} "
                  f"{lam[-1] / lam[0]:7.2f} {share:13.3f} {os.getloadavg()[0]:5.1f}", flush=True)


if __name__ == "__main__":
    main()
