"""Is the distributed auxiliary-space sweep symmetric positive definite? (issue 23: CG stopped with
KSP_DIVERGED_INDEFINITE_PC at 3-4 ranks). Run it under mpiexec:

    mpiexec -n 3 python benchmarks/distributed_sweep.py --cells 18 --fibres 900
    mpiexec -n 3 python benchmarks/distributed_sweep.py --cells 18 --fibres 900 --petsc-options "-mortar_beam_blocks rank"
    mpiexec -n 3 python benchmarks/distributed_sweep.py --cells 18 --fibres 900 --partition whole-beams \\
        --petsc-options "-mortar_beam_blocks rank -mortar_follow lumped"

The scene is that of benchmarks/distributed_scaling.py (linear). After the sweep's set-up (the
default PETSc options, or those of ``--petsc-options``: ``-mortar_beam_blocks rank`` the beam solve
on each rank's owned beam unknowns as before the fix, ``-mortar_follow lumped``, an exact beam
solve by MUMPS, ...) it measures, collectively, on the operator B of one application:

- ``asymmetry``: |xᵀ B y − yᵀ B x| / |xᵀ B y| for two random vectors;
- ``ritz_BA``: the smallest and largest Ritz values of the preconditioned operator B A after
  ``--lanczos`` Lanczos steps in A's energy inner product (with full reorthogonalisation, from a
  random vector): a negative smallest one proves B indefinite;
- ``beam_smoother``: the extreme eigenvalues of J⁻¹ A_bb (J: the beam solve, A_bb: its block), from
  the Lanczos coefficients of ``--lanczos`` CG steps (PETSc's KSPComputeExtremeSingularValues);
  the symmetric multiplicative sweep stays positive definite when they lie in (0, 2) (the beam
  correction ``I − J⁻¹ A_bb`` then does not grow any error in the energy norm);
- ``omega``: the smoothing's λ_max(D⁻¹ A_bb) as the sweep estimated it (10 Lanczos steps, at least
  1) and after ``--lanczos`` CG steps with Jacobi (whether the short estimate undershoots);

then runs CG (rtol 1e-8) and prints its iterations or PETSc's error. ``beams``: how many beams
the partition cuts, and over how many ranks at most. ``--partition whole-beams`` gives every beam
whole to the rank owning most of its elements in the METIS partition (to tell cut beams from the
rest), ``--partition dealt`` deals every beam's elements to the ranks in turn (element e to rank
e mod n: every beam cut at every node, the partition of tests/test_distributed.py's cut-beam test).
One JSON line on rank 0.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from distributed_scaling import scene       # noqa: E402


def lanczos_ritz(apply, A, steps, seed):
    """Extreme Ritz values of ``B A`` (``apply(x, y)``: y = B x, B symmetric) in the energy inner
    product of ``A`` (symmetric positive definite): ``steps`` Lanczos steps with full
    reorthogonalisation from a random vector (each rank its entries, seeded). B A is then
    A-symmetric and a negative Ritz value is one of its eigenvalues' bounds: B is indefinite."""
    rng = np.random.default_rng(seed)
    v, av = A.createVecs()
    v.setArray(rng.standard_normal(v.getLocalSize()))
    A.mult(v, av)
    norm = np.sqrt(v.dot(av))
    v.scale(1.0 / norm), av.scale(1.0 / norm)
    basis, alpha, beta = [(v, av)], [], []
    w, aw = v.duplicate(), v.duplicate()
    for _ in range(steps):
        apply(basis[-1][1], w)                    # w = B A v
        alpha.append(w.dot(basis[-1][1]))
        for _twice in range(2):                   # full reorthogonalisation (twice is enough)
            for u, au in basis:
                w.axpy(-w.dot(au), u)
        A.mult(w, aw)
        b = np.sqrt(max(w.dot(aw), 0.0))
        if b < 1e-14 * abs(alpha[-1]):
            break
        beta.append(b)
        basis.append((w.copy(), aw.copy()))
        basis[-1][0].scale(1.0 / b), basis[-1][1].scale(1.0 / b)
    k = len(alpha)
    T = np.diag(alpha) + np.diag(beta[:k - 1], 1) + np.diag(beta[:k - 1], -1)
    ritz = np.linalg.eigvalsh(T)
    for pair in basis + [(w, aw)]:
        pair[0].destroy(), pair[1].destroy()
    return float(ritz[0]), float(ritz[-1])


def extreme_eigenvalues(A, pc, steps, seed):
    """The extreme eigenvalues of ``pc⁻¹ A`` from ``steps`` CG steps (PETSc's estimate)."""
    from mortar1d3d.distributed.petsc import petsc
    PETSc = petsc()
    ksp = PETSc.KSP().create(comm=A.getComm())
    ksp.setOperators(A)
    ksp.setType(PETSc.KSP.Type.CG)
    ksp.setPC(pc)
    ksp.setComputeSingularValues(True)
    ksp.setTolerances(rtol=1e-30, atol=0.0, max_it=steps)
    ksp.setConvergenceTest(lambda *a: 0)       # keep going for all steps (stop at the maximum only)
    b, x = A.createVecs()
    b.setArray(np.random.default_rng(seed).standard_normal(b.getLocalSize()))
    ksp.solve(b, x)
    high, low = ksp.computeExtremeSingularValues()
    b.destroy(), x.destroy()
    return float(low), float(high)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=12)
    parser.add_argument("--fibres", type=int, default=300)
    parser.add_argument("--fibre-elements", type=int, default=10, metavar="N")
    parser.add_argument("--partition", choices=("metis", "whole-beams", "dealt"), default="metis")
    parser.add_argument("--lanczos", type=int, default=30, metavar="STEPS")
    parser.add_argument("--petsc-options", default="", metavar="OPTIONS")
    args = parser.parse_args()
    from mortar1d3d.distributed import auxiliary, partition
    from mortar1d3d.distributed.petsc import petsc
    from mortar1d3d.distributed.solve import solve_distributed
    PETSc = petsc()
    comm = PETSc.COMM_WORLD
    rank = comm.getRank()
    if args.petsc_options:
        PETSc.Options().insertString(args.petsc_options)
    found = {}

    def parts(solid, beams, n):
        p = partition(solid, beams, n, "metis")
        beam_part = list(p.beam_part)
        if args.partition == "whole-beams":
            beam_part = [auxiliary.whole_beam_part(b, bp, n) for b, bp in zip(beams, beam_part)]
        elif args.partition == "dealt":
            beam_part = [np.arange(b.n_elements) % n for b in beams]
        # ranks per beam: the distinct (beam, rank) pairs of each beam
        spread = [np.bincount(np.unique(auxiliary.beam_of_element(b) * n + bp) // n) for b, bp in zip(beams, beam_part)]
        found["beams"] = {"beams": int(sum(len(s) for s in spread)),
                          "cut": int(sum(np.count_nonzero(s > 1) for s in spread)),
                          "max_ranks_per_beam": int(max(s.max() for s in spread))}
        return p.solid_part, beam_part

    radius = auxiliary.beam_spectral_radius

    def recorded_radius(*a):
        found["omega_estimate"] = radius(*a)
        return found["omega_estimate"]
    auxiliary.beam_spectral_radius = recorded_radius
    set_up = auxiliary.AuxiliarySweep.setUp

    def diagnosed(self, pc):
        set_up(self, pc)
        x, y = self.A.createVecs()
        rng = np.random.default_rng(rank + 1)
        x.setArray(rng.standard_normal(x.getLocalSize()))
        y.setArray(rng.standard_normal(y.getLocalSize()))
        bx, by = x.duplicate(), y.duplicate()
        self.apply(pc, x, bx)
        self.apply(pc, y, by)
        found["asymmetry"] = abs(x.dot(by) - y.dot(bx)) / abs(x.dot(by))
        found["ritz_BA"] = lanczos_ritz(lambda u, v: self.apply(pc, u, v), self.A, args.lanczos, rank + 7)
        beam = self.beam.getOperators()[0]
        found["beam_smoother"] = extreme_eigenvalues(beam, self.beam.getPC(), args.lanczos, rank + 11)
        jacobi = PETSc.PC().create(comm=beam.getComm())
        jacobi.setType(PETSc.PC.Type.JACOBI)
        jacobi.setOperators(beam)
        found["omega"] = {"estimate": found.get("omega_estimate"),
                          f"cg_{args.lanczos}": extreme_eigenvalues(beam, jacobi, args.lanczos, rank + 13)[1]}
        jacobi.destroy()
        for v in (x, y, bx, by):
            v.destroy()
    auxiliary.AuxiliarySweep.setUp = diagnosed
    sc = scene(args.cells, args.fibres, None, args.fibre_elements)
    try:
        result = solve_distributed(sc, comm=comm, parts=parts)
        outcome = {"iterations": result.distributed["iterations"]} if rank == 0 else {}
    except Exception as exc:          # every rank raises the same (PETSc's converged reason is collective)
        outcome = {"error": str(exc)[:160]}
    if rank == 0:
        found.pop("omega_estimate", None)
        print(json.dumps({"ranks": comm.getSize(), "cells": args.cells, "fibres": args.fibres,
                          "fibre_elements": args.fibre_elements, "partition": args.partition,
                          "petsc_options": args.petsc_options, **outcome, **found}))


if __name__ == "__main__":
    main()
