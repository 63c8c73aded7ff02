"""CG on the solid's Schur complement of the penalty system: the beam DOFs eliminated exactly with
the banded factor of the auxiliary space, the solid preconditioned by its AMG V-cycle."""
import numpy as np
import scipy.sparse.linalg as spla

from .krylov import roundoff_level, run_krylov
from .preconditioners import _row_block

__all__ = ["SchurComplement", "schur_cg"]


class SchurComplement:
    """``S = A_SS − A_SB A_BB⁻¹ A_BS`` of a penalty system, applied without forming it.

    Parameters
    ----------
    preconditioner : AuxiliarySpacePreconditioner
        Built for ``A``; its solid/beam split and its factor of ``A_BB`` are used.

    Attributes
    ----------
    shape : (n_s, n_s)

    Notes
    -----
    One product costs one product with the solid rows of ``A`` (``[A_SS, A_SB]``), one with
    ``A_BS`` and one banded solve with ``A_BB``; the auxiliary-space sweep on the whole system
    costs a product with ``A`` in CG, two banded solves and the products with ``A_SB`` and ``A_BS``.
    The Schur complement of ``A`` in the basis ``[d_S; d_B − P d_S]`` is the same ``S`` (a change
    of basis of the beam block only), so its V-cycle on ``A_aux = Eᵀ A E ≥ S`` is the
    preconditioner here as it is inside the auxiliary-space sweep.
    """

    def __init__(self, preconditioner):
        pre = preconditioner
        self._s, self._b = pre._s, pre._b
        self.n = pre.shape[0]
        A = pre.A
        if isinstance(self._s, slice) and A.format == "csr":
            # the solid rows of A as they are (the model numbers the solid DOFs first): no copy of
            # them (get_csr_submatrix took 0.1 CPU s at n = 20 of fibre_cube(n, 1000, 20))
            self.rows = _row_block(A, self._s)                 # [A_SS, A_SB]
        else:
            self.rows = A[self._s].tocsr()
        self.coupling = pre.A_bs                              # A_BS
        self.factor = pre._beam_factor
        n_s = self.rows.shape[0]
        self.shape = (n_s, n_s)

    def beam(self, x_s, b_b):
        """The beam DOFs that balance ``x_s``: ``A_BB⁻¹ (b_B − A_BS x_S)``."""
        return self.factor.solve(b_b - self.coupling @ x_s)

    def whole(self, x_s, b):
        """The full vector ``[x_S; x_B]`` with ``x_B`` from :meth:`beam` for the right-hand side ``b``."""
        x = np.empty(self.n)
        x[self._s] = x_s
        x[self._b] = self.beam(x_s, b[self._b])
        return x

    def matvec(self, x_s):
        """``S x_S``."""
        return self.rows @ self.whole(x_s, np.zeros(self.n))

    def rhs(self, b):
        """``b_S − A_SB A_BB⁻¹ b_B``: the right-hand side of the reduced system."""
        return b[self._s] - self.rows @ self.whole(np.zeros(self.shape[0]), b)


def schur_cg(A, b, preconditioner, x, rtol, maxiter):
    """Solve the penalty system ``A x = b`` by CG on the solid's Schur complement.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, SPD
    b, x : (n,) ndarray of float
        Right-hand side and start vector (its solid part is CG's start).
    preconditioner : AuxiliarySpacePreconditioner
        Built for this ``A``: the complement takes ``A``'s rows and beam factor from it
        (:func:`~mortar1d3d.solvers.linear.solve_linear` runs the auxiliary-space sweep instead when
        the preconditioner was kept from another matrix).
    rtol : float
        Relative residual ``‖b − A x‖ / ‖b‖`` of the whole system to reach.
    maxiter : int

    Returns
    -------
    x : (n,) ndarray
    outcome : dict
        ``iterations``, ``residual`` (of the whole system) and ``status`` as
        :func:`~mortar1d3d.solvers.krylov.run_krylov` gives them.

    Notes
    -----
    With ``x_B`` eliminated exactly, the residual of the whole system is ``[r_S; 0]`` with
    ``r_S = rhs − S x_S``: CG's residual on ``S`` is the whole system's, so ``rtol`` means what it
    means for the other paths. The true residual is checked on ``A`` itself. On
    ``fibre_cube(n, 1000, 20)`` (ε = 1e3 E) the iterations equal those of the auxiliary-space
    sweep on ``A`` (20 at n = 20 with the preconditioner's ``LUMPED`` settings; not measured with
    its smoothed prolongation) and each is cheaper (benchmarks/README.md, "The solid's Schur
    complement").
    """
    S = SchurComplement(preconditioner)
    bnorm = np.linalg.norm(b)
    cycle = preconditioner._cycle.matvec

    def residual(x_s):
        return np.linalg.norm(b - A @ S.whole(x_s, b)) / bnorm

    def floor(x_s):
        return roundoff_level(A, S.whole(x_s, b), b)

    operator = spla.LinearOperator(S.shape, matvec=S.matvec, dtype=float)
    x_s, iterations, res, status = run_krylov("cg", operator, S.rhs(b), x[S._s].copy(), cycle, rtol, maxiter,
                                              residual, floor)
    return S.whole(x_s, b), dict(iterations=iterations, residual=res, status=status)
