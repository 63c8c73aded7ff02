"""What every linear solver module shares: the error it raises and the checks of its arguments."""
import numpy as np
import scipy.sparse as sp

from ..errors import LinearSolverError  # noqa: F401 (raised by every solver module)

__all__ = ["LinearSolverError", "check_square", "check_vector", "split_dofs"]


def check_square(A, name):
    if not sp.issparse(A):
        raise TypeError(f"{name} must be a scipy.sparse matrix, got {type(A).__name__}")
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be square, got shape {A.shape}")
    return A.tocsr()


def check_vector(v, n, name):
    v = np.asarray(v, dtype=np.float64)
    if v.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {v.shape}")
    return v


def split_dofs(n, solid, beam):
    """``(solid, beam)``: int64 index arrays that partition ``0..n-1`` (checked); default all solid."""
    if solid is None and beam is None:
        return np.arange(n), np.zeros(0, dtype=np.int64)
    solid = np.arange(n) if solid is None else np.asarray(solid, dtype=np.int64)
    if beam is None:
        beam = np.setdiff1d(np.arange(n), solid)
    beam = np.asarray(beam, dtype=np.int64)
    cover = np.zeros(n, dtype=np.int64)
    np.add.at(cover, solid, 1)
    np.add.at(cover, beam, 1)
    if np.any(cover != 1):
        raise ValueError("solid and beam must partition the free DOFs 0..n-1 (each exactly once)")
    return solid, beam
