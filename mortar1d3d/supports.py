"""Clamped beam tangents: a support that fixes a direction, held in a rotated basis.

At a node of a Hermite (``torsion_free``) beam the tangent vector ``t`` is an unknown; its length
is the local stretch of the centreline. A clamp must fix the direction of ``t`` and leave its
length free, i.e. ``e1·Δt = 0`` and ``e2·Δt = 0`` with two unit vectors ``e1, e2`` orthogonal
to the reference unit tangent ``t0``. In the coordinates of the orthonormal frame
``(e1, e2, t0)`` these are two plain zero-valued DOFs, whatever the direction of the beam.

:class:`RotatedBasis` is that change of coordinates for the whole vector of unknowns: the
solvers see ``z̃`` with ``z = T z̃`` (``T`` orthogonal, the identity except on the clamped
tangent triplets), so residuals become ``Tᵀ r`` and tangents ``Tᵀ K T``. Fixed/free DOF
indices, rigid-body modes, preconditioner data and the solution vector of a solve all live in
this basis; the physics (elements, coupling, loads) is evaluated on ``T z̃``.
"""
import numpy as np
import scipy.sparse as sp


def clamp_frame(t0):
    """Rows ``(e1, e2, t0/|t0|)``: a right-handed orthonormal frame whose third axis is ``t0``.

    ``e1`` is built from the coordinate axis least aligned with ``t0``, so the frame depends
    continuously on ``t0`` away from ties and is well conditioned for every direction.
    """
    t = np.asarray(t0, dtype=float)
    t = t / np.linalg.norm(t)
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(t)))] = 1.0
    e1 = np.cross(t, helper)
    e1 /= np.linalg.norm(e1)
    return np.array([e1, np.cross(t, e1), t])


class RotatedBasis:
    """Orthogonal change of basis ``z = T z̃`` acting on DOF triplets.

    Parameters
    ----------
    starts : (k,) int
        First DOF of each rotated triplet (distinct).
    frames : (k, 3, 3) float
        Per triplet, the rows are the new basis vectors: ``z̃[s:s+3] = F z[s:s+3]``.

    With ``k = 0`` every method returns its input unchanged (no copies, no products).
    """

    def __init__(self, starts=(), frames=()):
        self.starts = np.asarray(starts, dtype=np.int64).reshape(-1)
        self.frames = np.asarray(frames, dtype=float).reshape(-1, 3, 3)
        if len(np.unique(self.starts)) != len(self.starts):
            raise ValueError("RotatedBasis: a DOF triplet is given more than once")
        self._rows = (self.starts[:, None] + np.arange(3)).ravel()
        self._T = {}

    def __bool__(self):
        return bool(len(self.starts))

    def _apply(self, v, inverse, offset):
        if not self:
            return v
        if sp.issparse(v):
            T = self.matrix_T(offset + v.shape[0])[offset:, offset:]
            return (T @ v if inverse else T.T @ v).tocsr()
        out = np.array(v, dtype=float, copy=True)
        rows = self._rows - offset
        block = out[rows].reshape(len(self.starts), 3, -1)
        frames = np.transpose(self.frames, (0, 2, 1)) if inverse else self.frames
        out[rows] = np.einsum("kij,kjm->kim", frames, block).reshape(out[rows].shape)
        return out

    def to_unknowns(self, v, offset=0):
        """``Tᵀ v`` for a vector, dense (n, m) array or sparse matrix whose row 0 is DOF ``offset``
        (physical residuals, rigid-body modes, prolongations → the solvers' basis)."""
        return self._apply(v, False, offset)

    def to_physical(self, v, offset=0):
        """``T v``: unknowns (or residuals) of the solvers' basis → physical components."""
        return self._apply(v, True, offset)

    def matrix_T(self, n):
        """``T`` as an (n, n) CSR matrix (cached per size)."""
        if n not in self._T:
            keep = np.ones(n, dtype=bool)
            keep[self._rows] = False
            ident = np.flatnonzero(keep)
            k = len(self.starts)
            # T[s + i, s + j] = F[j, i]: the columns of each block are the new basis vectors
            rows = np.concatenate([ident, np.repeat(self._rows, 3)])
            cols = np.concatenate([ident, (self.starts[:, None, None] + np.zeros((1, 3, 3), np.int64)
                                           + np.arange(3)[None, None, :]).ravel()])
            vals = np.concatenate([np.ones(len(ident)), np.transpose(self.frames, (0, 2, 1)).reshape(k * 9)])
            self._T[n] = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
        return self._T[n]

    def matrix(self, K):
        """``Tᵀ K T`` for a square sparse matrix over the unknowns (from DOF 0)."""
        if not self or K is None:
            return K
        T = self.matrix_T(K.shape[0])
        return (T.T @ K @ T).tocsr()
