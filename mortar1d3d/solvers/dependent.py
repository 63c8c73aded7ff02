"""Rows of a mortar constraint matrix that depend on the others (a multiplier space richer than
what the solid resolves along a beam), and the least-norm multipliers without them."""
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

__all__ = ["DEPENDENT_ROW_TOLERANCE", "DependentRows", "dependent_rows"]

#: rows of ``B`` count as dependent when a combination of them with unit coefficient norm (rows
#: and columns first scaled to unit size) is shorter than this: the multipliers of such rows
#: would carry less than half of the working digits (their error grows like eps / length),
#: while dropping one leaves a constraint violation of at most this relative size
DEPENDENT_ROW_TOLERANCE = float(np.sqrt(np.finfo(float).eps))


@dataclass
class DependentRows:
    """Rows of a constraint matrix ``B`` that depend on the others (see :func:`dependent_rows`).

    Attributes
    ----------
    rows : (d,) ndarray of int64
        The dependent rows (ids of rows of ``B``, sorted); the other rows are independent.
    combinations : (d, m) scipy.sparse.csr_matrix
        A basis of the left null space of ``B`` (``combinations @ B ≈ 0``); row k has
        coefficient 1 at ``rows[k]`` and 0 at the other dependent rows.
    n_rows : int
        ``m``, the number of rows of ``B``.
    """

    rows: np.ndarray
    combinations: object
    n_rows: int

    def __len__(self):
        return len(self.rows)

    def least_norm(self, lam, weight):
        """``lam`` plus the null-space combination that minimises ``Σ weight λ²``.

        ``Bᵀλ``, the forces the multipliers transfer, is unchanged; of all multipliers that
        transfer them this is the one of least weighted norm, so the answer does not depend on
        which of the dependent rows were dropped.
        """
        if not len(self):
            return lam
        C = self.combinations
        Cw = (C @ sp.diags(weight)).tocsr()
        y = spla.spsolve((Cw @ C.T).tocsc(), Cw @ lam)
        return lam - C.T @ np.atleast_1d(y)


def _components(A):
    """Connected-component label of every row of ``A`` (rows are connected by shared columns)."""
    pattern = A.tocsr(copy=True)
    pattern.data = np.ones_like(pattern.data)
    return connected_components(pattern @ pattern.T, directed=False)[1]


def _groups(label):
    order = np.argsort(label, kind="stable")
    return np.split(order, np.flatnonzero(np.diff(label[order])) + 1)


def _row_rank(A, tolerance):
    """Rank of the rows of the dense ``A``, pivot order and ``R`` of a column-pivoted QR of ``Aᵀ``."""
    R, piv = sla.qr(A.T, mode="r", pivoting=True)
    diag = np.abs(np.diag(R))
    return int(np.count_nonzero(diag > tolerance)), piv, R


def dependent_rows(B, beam=None, *, tolerance=DEPENDENT_ROW_TOLERANCE):
    """Rows of a mortar constraint matrix that are (numerically) combinations of the others.

    Parameters
    ----------
    B : (m, n) scipy.sparse matrix
        Constraint rows ``[-M, D]`` on the free DOF columns. Empty rows (all their columns
        eliminated) constrain nothing and are left out.
    beam : (n_b,) array_like of int, optional
        The beam DOF columns (the ``D`` part); default none (every column a solid DOF).
    tolerance : float
        See :data:`DEPENDENT_ROW_TOLERANCE`.

    Returns
    -------
    DependentRows

    Notes
    -----
    A dense rank decision on all of ``B`` would cost ``O(m² n)``; the structure makes it local.
    Columns are scaled to unit largest entry and then rows to unit length, so that neither the
    units of tangent DOFs nor short LM supports sway the decision. Rows are grouped by the beam
    columns they share (one group per beam and component: x, y and z rows never share a
    column) and a column-pivoted QR of each group's rows finds the dependent ones. Rows of
    different groups can only depend on each other through combinations whose beam part
    vanishes, i.e. through the left null space ``Z`` of each group's beam block (usually empty:
    ``D`` has full row rank unless the multiplier space is richer than the centreline or
    Dirichlet conditions removed beam columns). The rows ``Zᵀ M`` of all groups, grouped again
    by the solid columns they share, are tested the same way; a pivoted QR of the dependent
    combinations then chooses the rows to drop so that the remaining ones are independent.
    """
    B = B.tocsr()
    m, n = B.shape
    if B.nnz == 0:
        return DependentRows(np.zeros(0, np.int64), sp.csr_matrix((0, m)), m)
    is_beam = np.zeros(n, dtype=bool)
    if beam is not None:
        is_beam[np.asarray(beam, dtype=np.int64)] = True
    column = np.asarray(abs(B).max(axis=0).todense()).ravel()
    column[column == 0] = 1.0
    Bn = (B @ sp.diags(1.0 / column)).tocsr()
    length = np.sqrt(np.asarray(Bn.multiply(Bn).sum(axis=1)).ravel())
    # empty rows constrain nothing (no multiplier): they are neither dependent nor independent
    scale = np.divide(1.0, length, out=np.zeros(m), where=length > 0)
    Bn = (sp.diags(scale) @ Bn).tocsr()
    Bn.eliminate_zeros()
    dropped, combos = [], []        # combos: (rows, coefficients) of scaled rows
    stage2 = []                     # per group: kept rows, Z, Zᵀ M (dense), its solid columns
    label = _components(Bn[:, is_beam])
    label[length == 0] = -1
    for rows in _groups(label):
        if length[rows[0]] == 0:
            continue
        block = Bn[rows]
        cols = np.unique(block.indices)
        dense = block[:, cols].toarray()
        rank, piv, R = _row_rank(dense, tolerance)
        if rank < len(rows):
            # each dependent pivot row in terms of the first `rank` ones: [-R11⁻¹ R12; I]
            top = -sla.solve_triangular(R[:rank, :rank], R[:rank, rank:len(rows)]) if rank else \
                np.zeros((0, len(rows)))
            for k in range(len(rows) - rank):
                dropped.append(rows[piv[rank + k]])
                combos.append((rows[np.append(piv[:rank], piv[rank + k])], np.append(top[:, k], 1.0)))
        kept = dense[piv[:rank]]
        on_beam = is_beam[cols]
        if on_beam.any():
            U, s, _ = np.linalg.svd(kept[:, on_beam], full_matrices=True)
            Z = U[:, int(np.count_nonzero(s > tolerance)):]
        else:
            Z = np.eye(rank)
        if Z.shape[1]:
            stage2.append((rows[piv[:rank]], Z, Z.T @ kept[:, ~on_beam], cols[~on_beam]))
    if stage2:
        parts = []
        for _, Z, solid, cols in stage2:
            k, c = solid.shape
            parts.append(sp.csr_matrix((solid.ravel(), (np.repeat(np.arange(k), c), np.tile(cols, k))), shape=(k, n)))
        T = sp.vstack(parts, format="csr")
        owner = np.concatenate([np.full(Z.shape[1], i) for i, (_, Z, _, _) in enumerate(stage2)])
        betas = []                  # dependent combinations of rows of T
        for t_rows in _groups(_components(T)):
            block = T[t_rows]
            cols = np.unique(block.indices)
            if len(cols) == 0:
                beta = np.eye(len(t_rows))
            else:
                rank, piv, R = _row_rank(block[:, cols].toarray(), tolerance)
                if rank == len(t_rows):
                    continue
                beta = np.zeros((len(t_rows), len(t_rows) - rank))
                if rank:
                    beta[piv[:rank]] = -sla.solve_triangular(R[:rank, :rank], R[:rank, rank:len(t_rows)])
                beta[piv[rank:]] = np.eye(len(t_rows) - rank)
            full = np.zeros((len(T.indptr) - 1, beta.shape[1]))
            full[t_rows] = beta
            betas.append(full)
        if betas:
            beta = np.hstack(betas)
            # the combinations over the kept rows of the groups involved: α = Z β, group by group
            involved = np.unique(owner[np.any(beta != 0, axis=1)])
            rows = np.concatenate([stage2[i][0] for i in involved])
            alpha = np.vstack([stage2[i][1] @ beta[owner == i] for i in involved])
            d = alpha.shape[1]
            _, _, piv = sla.qr(alpha.T, mode="economic", pivoting=True)
            # a basis with coefficient 1 at its own dropped row and 0 at the others
            alpha = alpha @ np.linalg.inv(alpha[piv[:d]])
            for k in range(d):
                dropped.append(rows[piv[k]])
                use = alpha[:, k] != 0
                combos.append((rows[use], alpha[use, k]))
    if not dropped:
        return DependentRows(np.zeros(0, np.int64), sp.csr_matrix((0, m)), m)
    r = np.concatenate([rows for rows, _ in combos])
    k = np.concatenate([np.full(len(rows), i) for i, (rows, _) in enumerate(combos)])
    v = np.concatenate([coef for _, coef in combos]) * scale[r]       # back to the rows of B
    C = sp.csr_matrix((v, (k, r)), shape=(len(combos), m))
    order = np.argsort(dropped)
    return DependentRows(np.asarray(dropped, dtype=np.int64)[order], C[order], m)
