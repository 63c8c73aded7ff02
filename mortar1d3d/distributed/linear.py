"""The linear solves of the distributed system: PETSc KSP with the preconditioner ``analysis.solver`` asks for.

* penalty coupling (a symmetric positive definite system): CG on the true residual (``"auto"``,
  ``"amg"``) with the auxiliary-space sweep (:mod:`.auxiliary`), or with PETSc's algebraic
  multigrid GAMG on the whole system, given the model's rigid-body modes as near-null space
  (``-mortar_penalty_pc gamg``), the preconditioner kept over a Newton loop's solves while they
  converge nearly as fast; or MUMPS' parallel LU (``"direct"``);
* Lagrange multipliers (a saddle point ``[[K, Bᵀ], [B, 0]]``): MUMPS on the whole system
  (``"direct"``, and ``"auto"``: the fallback for small cases), or (``"block"``) FGMRES with a
  Schur-complement field split (:class:`LinearSolver`, ``split``).
"""
import time

import numpy as np

from .petsc import petsc


def null_space(modes, comm):
    """The rigid-body modes as an orthonormal PETSc null space (this rank's entries: ``modes``)."""
    PETSc = petsc()
    vecs = []
    for mode in modes:
        v = PETSc.Vec().createMPI((len(mode), PETSc.DECIDE), comm=comm)
        v.setArray(np.ascontiguousarray(mode))
        vecs.append(v)
    # PETSc wants an orthonormal basis
    for j, v in enumerate(vecs):
        for u in vecs[:j]:
            v.axpy(-v.dot(u), u)
        v.normalize()
    return PETSc.NullSpace().create(vectors=vecs, comm=comm)


#: PETSc's KSP_DIVERGED_INDEFINITE_PC: CG met a preconditioner that is not positive definite
DIVERGED_INDEFINITE_PC = -8


def divergence_hint(method, reason):
    """What a user can do when a penalty solve did not converge for ``reason`` (PETSc's converged
    reason), appended to the error; empty where there is nothing specific to say."""
    if method == "aux" and reason == DIVERGED_INDEFINITE_PC:
        return ("; the auxiliary-space sweep became indefinite, as it can with -mortar_beam_blocks rank where the "
                "partition cuts a beam across three or more ranks (the beam solve is then not a convergent smoother; "
                "docs/distributed.md): leave out -mortar_beam_blocks rank (whole beams, the default), solve the beam "
                "block with -mortar_beam_pc_type lu -mortar_beam_pc_factor_mat_solver_type mumps, or take GAMG "
                "on the whole system with -mortar_penalty_pc gamg")
    return ""


class LinearSolver:
    """One KSP configuration, applied to each tangent system.

    Parameters
    ----------
    method : {"gamg", "aux", "mumps", "schur"}
        ``aux``: the auxiliary-space sweep of the penalty system (:mod:`.auxiliary`).
    near_null_space : list of (n_owned,) arrays, optional
        Owned entries of the rigid-body modes (GAMG).
    split : dict, optional
        ``schur``: ``displacements``, ``multipliers`` (owned system indices of each field) and
        ``augmentation`` (see :meth:`_schur`).
    symmetric : bool
        False (follower loads of a nonlinear analysis): GAMG preconditions GMRES (restarted after
        200 iterations) instead of CG.
    auxiliary : dict, optional
        ``aux``: the arguments of :class:`~.auxiliary.AuxiliarySweep`.
    reuse : bool
        ``gamg`` and ``aux``: keep the KSP and its preconditioner for the next solves (a Newton
        loop's next tangents) while they converge nearly as fast as the solve that built it, the
        serial policy (:mod:`mortar1d3d.solvers.reuse`): a solve that needs more than
        ``REBUILD_GROWTH`` times its iterations plus ``REBUILD_SLACK`` drops it, one that does
        not converge with it is repeated with a new one.

    Attributes
    ----------
    builds, reuses : int
        Solves that set a preconditioner up, and solves that used a kept one.
    """

    block_size = 3

    def __init__(self, method, near_null_space=None, split=None, symmetric=True, auxiliary=None, reuse=False):
        self.method, self.modes, self.split, self.symmetric = method, near_null_space, split, symmetric
        self.auxiliary = auxiliary
        self.reuse = bool(reuse) and method in ("gamg", "aux")
        self._kept, self._built_iterations = None, 0
        self.builds = self.reuses = 0

    def close(self):
        """Free the kept KSP (its preconditioner references an earlier tangent)."""
        if self._kept is not None:
            self._kept.destroy()
            self._kept = None

    def solve(self, A, b, x, rtol):
        """Solve ``A x = b`` to the relative true residual ``rtol`` (iterative methods); returns the info dict."""
        from ..errors import ConvergenceError
        from ..solvers.reuse import REBUILD_GROWTH, REBUILD_SLACK
        if self._kept is not None:
            ksp, self._kept = self._kept, None
            ksp.setOperators(A)
            ksp.getPC().setReusePreconditioner(True)
            ksp.setTolerances(rtol=rtol, atol=0.0, max_it=10000)
            info, reason = self._run(ksp, A, b, x, rtol)
            if reason >= 0:
                self.reuses += 1
                info["reused"] = True
                if info["iterations"] <= REBUILD_GROWTH * self._built_iterations + REBUILD_SLACK:
                    self._kept = ksp
                else:
                    ksp.destroy()
                return info
            ksp.destroy()           # not converged with the kept preconditioner: a new one
        ksp, A, b = self._configure(A, b, rtol)
        info, reason = self._run(ksp, A, b, x, rtol)
        self.builds += 1
        info["reused"] = False
        if self.reuse and reason >= 0:
            self._kept, self._built_iterations = ksp, info["iterations"]
        else:
            # freed now: the KSP and its preconditioner (GAMG's hierarchy, MUMPS' factors) reference the
            # operators, and petsc4py left them to the garbage collector, which let a Newton run grow by
            # a hierarchy per iteration (65 MiB per iteration at 8k unknowns)
            ksp.destroy()
        if reason < 0:
            raise ConvergenceError(f"PETSc KSP {info['ksp']} with {info['pc']} did not converge "
                                   f"(reason {reason}) after {info['iterations']} iterations"
                                   + divergence_hint(self.method, reason))
        return info

    def _configure(self, A, b, rtol):
        """A new KSP for ``A`` (the Schur split: for the augmented system it returns with its right side)."""
        PETSc = petsc()
        ksp = PETSc.KSP().create(comm=A.getComm())
        ksp.setOperators(A)
        if self.method == "mumps":
            ksp.setType(PETSc.KSP.Type.PREONLY)
            ksp.getPC().setType(PETSc.PC.Type.LU)
            ksp.getPC().setFactorSolverType("mumps")
        elif self.method in ("gamg", "aux"):
            ksp.setType(PETSc.KSP.Type.CG if self.symmetric else PETSc.KSP.Type.GMRES)
            if not self.symmetric:
                # GMRES(30) stalls on penalty systems (an end moment on the rebar cantilever: no
                # convergence in 10,000 iterations; unrestarted, 45): restarted only after 200
                ksp.setGMRESRestart(200)
            # the true residual, as analysis.rtol means for the serial solvers (not the preconditioned one)
            ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
            if self.method == "gamg":
                A.setNearNullSpace(null_space(self.modes, A.getComm()))
                ksp.getPC().setType(PETSc.PC.Type.GAMG)
            else:
                from .auxiliary import AuxiliarySweep
                ksp.getPC().setType(PETSc.PC.Type.PYTHON)
                ksp.getPC().setPythonContext(AuxiliarySweep(**self.auxiliary))
            ksp.setTolerances(rtol=rtol, atol=0.0, max_it=10000)
        else:
            A, b = self._schur(ksp, A, b, rtol)
        ksp.setFromOptions()
        return ksp, A, b

    def _run(self, ksp, A, b, x, rtol):
        """One solve with ``ksp`` (set up first, if it is not): the info dict and PETSc's converged reason."""
        x.set(0.0)
        start = time.perf_counter()
        ksp.setUp()
        set_up = time.perf_counter()
        ksp.solve(b, x)
        info = {"iterations": ksp.getIterationNumber(), "ksp": ksp.getType(), "pc": ksp.getPC().getType(),
                "setup_seconds": set_up - start, "solve_seconds": time.perf_counter() - set_up}
        return info, ksp.getConvergedReason()

    def _schur(self, ksp, A, b, rtol):
        """FGMRES with a Schur-complement field split of the augmented saddle point.

        The system ``[[K, Bᵀ], [B, 0]] [u; λ] = [f; g]`` (supports removed) is first multiplied by
        ``T = [[I, Bᵀ W], [0, I]]`` with ``W = diag(γ / κ)`` per multiplier row (κ of its LM
        node): ``[[K + Bᵀ W B, Bᵀ], [B, 0]] [u; λ] = [f + Bᵀ W g; g]``, which has the same
        solution (it adds W times the constraint rows to the equilibrium rows) and a displacement
        block that is the penalty stiffness (positive definite even where a beam is held only by the
        coupling). The field split then solves the displacement block by CG + GAMG (rigid-body
        modes, to 1e-8) and preconditions the Schur complement ``S = −B (K + Bᵀ W B)⁻¹ Bᵀ`` by
        ``−W⁻¹ = −diag(κ / γ)`` (applied by Jacobi), the limit of S where ``Bᵀ W B`` dominates K:
        the documented Schur preconditioner. γ is the solid's Young's modulus, which puts ``Bᵀ W B``
        at the scale of the solid's stiffness (examples/scenes/lagrange_pullout.toml at rtol 1e-12:
        9 FGMRES iterations, λ to 3e-8 at 2 ranks; with γ = 1e3 E 3 iterations, but λ only to 4e-6,
        the residual test then seeing mostly the augmented rows).
        """
        PETSc = petsc()
        split = self.split
        U = split["transform"]                      # T − I, the supports' rows zeroed
        A = A.copy()
        A.axpy(1.0, U.matMult(A), structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        b = b.copy()
        b.axpy(1.0, U * b)
        is_u = PETSc.IS().createGeneral(split["displacements"].astype(PETSc.IntType), comm=A.getComm())
        is_u.setBlockSize(3)
        is_l = PETSc.IS().createGeneral(split["multipliers"].astype(PETSc.IntType), comm=A.getComm())
        is_u.compose("nearnullspace", null_space(self.modes, A.getComm()))
        ksp.setOperators(A)
        ksp.setType(PETSc.KSP.Type.FGMRES)
        ksp.setTolerances(rtol=rtol, atol=0.0, max_it=2000)
        ksp.setGMRESRestart(200)
        pc = ksp.getPC()
        pc.setType(PETSc.PC.Type.FIELDSPLIT)
        pc.setFieldSplitIS(("u", is_u), ("lambda", is_l))
        pc.setFieldSplitType(PETSc.PC.CompositeType.SCHUR)
        pc.setFieldSplitSchurFactType(PETSc.PC.SchurFactType.FULL)
        pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, split["schur"])
        ksp.setUp()
        inner, schur = pc.getFieldSplitSubKSP()
        inner.setType(PETSc.KSP.Type.CG)
        inner.getPC().setType(PETSc.PC.Type.GAMG)
        inner.setTolerances(rtol=1e-8, atol=0.0, max_it=10000)
        schur.setType(PETSc.KSP.Type.PREONLY)
        schur.getPC().setType(PETSc.PC.Type.JACOBI)
        return A, b
