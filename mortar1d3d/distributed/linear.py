"""The linear solves of the distributed system: PETSc KSP with the preconditioner ``analysis.solver`` asks for.

* penalty coupling (a symmetric positive definite system): CG on the true residual with PETSc's
  algebraic multigrid GAMG, given the model's rigid-body modes as near-null space (``"auto"``,
  ``"amg"``), or MUMPS' parallel LU (``"direct"``);
* Lagrange multipliers (a saddle point ``[[K, Bᵀ], [B, 0]]``): MUMPS on the whole system
  (``"direct"``, and ``"auto"``: the fallback for small cases), or (``"block"``) FGMRES with a
  Schur-complement field split (:class:`LinearSolver`, ``split``).
"""
import numpy as np

from .petsc import petsc


class LinearSolver:
    """One KSP configuration, applied to each tangent system.

    Parameters
    ----------
    method : {"gamg", "mumps", "schur"}
    near_null_space : list of (n_owned,) arrays, optional
        Owned entries of the rigid-body modes (GAMG).
    split : dict, optional
        ``schur``: ``displacements``, ``multipliers`` (owned system indices of each field) and
        ``augmentation`` (see :meth:`_schur`).
    symmetric : bool
        False (follower loads of a nonlinear analysis): GAMG preconditions GMRES (restarted after
        200 iterations) instead of CG.
    """

    block_size = 3

    def __init__(self, method, near_null_space=None, split=None, symmetric=True):
        self.method, self.modes, self.split, self.symmetric = method, near_null_space, split, symmetric

    def _null_space(self, comm):
        """The rigid-body modes as an orthonormal PETSc null space (this rank's entries: ``self.modes``)."""
        PETSc = petsc()
        vecs = []
        for mode in self.modes:
            v = PETSc.Vec().createMPI((len(mode), PETSc.DECIDE), comm=comm)
            v.setArray(np.ascontiguousarray(mode))
            vecs.append(v)
        # PETSc wants an orthonormal basis
        for j, v in enumerate(vecs):
            for u in vecs[:j]:
                v.axpy(-v.dot(u), u)
            v.normalize()
        return PETSc.NullSpace().create(vectors=vecs, comm=comm)

    def solve(self, A, b, x, rtol):
        """Solve ``A x = b`` to the relative true residual ``rtol`` (iterative methods); returns the info dict."""
        from ..errors import ConvergenceError
        PETSc = petsc()
        ksp = PETSc.KSP().create(comm=A.getComm())
        ksp.setOperators(A)
        if self.method == "mumps":
            ksp.setType(PETSc.KSP.Type.PREONLY)
            ksp.getPC().setType(PETSc.PC.Type.LU)
            ksp.getPC().setFactorSolverType("mumps")
        elif self.method == "gamg":
            A.setNearNullSpace(self._null_space(A.getComm()))
            ksp.setType(PETSc.KSP.Type.CG if self.symmetric else PETSc.KSP.Type.GMRES)
            if not self.symmetric:
                # GMRES(30) stalls on penalty systems (an end moment on the rebar cantilever: no
                # convergence in 10,000 iterations; unrestarted, 45): restarted only after 200
                ksp.setGMRESRestart(200)
            # the true residual, as analysis.rtol means for the serial solvers (not the preconditioned one)
            ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
            ksp.getPC().setType(PETSc.PC.Type.GAMG)
            ksp.setTolerances(rtol=rtol, atol=0.0, max_it=10000)
        else:
            A, b = self._schur(ksp, A, b, rtol)
        ksp.setFromOptions()
        x.set(0.0)
        ksp.solve(b, x)
        reason = ksp.getConvergedReason()
        info = {"iterations": ksp.getIterationNumber(), "ksp": ksp.getType(), "pc": ksp.getPC().getType()}
        # freed now: the KSP and its preconditioner (GAMG's hierarchy, MUMPS' factors) reference the
        # operators, and petsc4py left them to the garbage collector, which let a Newton run grow by
        # a hierarchy per iteration (65 MiB per iteration at 8k unknowns)
        ksp.destroy()
        if reason < 0:
            raise ConvergenceError(f"PETSc KSP {info['ksp']} with {info['pc']} did not converge "
                                   f"(reason {reason}) after {info['iterations']} iterations")
        return info

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
        is_u.compose("nearnullspace", self._null_space(A.getComm()))
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
