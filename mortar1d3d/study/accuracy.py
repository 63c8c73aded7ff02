"""How far a variant's operators are from the reference: the errors of D, M and κ."""
import math

import numpy as np


def operator_errors(ops, reference):
    """Errors of D, M and κ against ``reference`` (same scene and LM type).

    Returns ``{"D_fro", "M_fro", "D_max", "M_max", "kappa_max"}``: relative Frobenius norm of the
    difference, and the worst entry over the largest entry of the reference.
    """
    out = {}
    for name in ("D", "M"):
        A, B = getattr(ops, name).tocsr(), getattr(reference, name).tocsr()
        diff = (A - B).tocoo()
        ref_norm = math.sqrt(float(B.multiply(B).sum()))
        ref_max = float(abs(B).max()) if B.nnz else 0.0
        d_norm = math.sqrt(float((diff.data ** 2).sum()))
        d_max = float(np.abs(diff.data).max()) if diff.nnz else 0.0
        out[f"{name}_fro"] = d_norm / ref_norm if ref_norm > 0 else d_norm
        out[f"{name}_max"] = d_max / ref_max if ref_max > 0 else d_max
    k_ref = np.abs(reference.kappa).max()
    out["kappa_max"] = float(np.abs(ops.kappa - reference.kappa).max() / k_ref) if k_ref > 0 else 0.0
    return out


def dm_error(record):
    """The error of one variant's operators that the report ranks by: ``max(D_fro, M_fro)``."""
    return max(record["D_fro"], record["M_fro"])


def u_error(record):
    """The monitor displacement error of one variant (None where the monitor did not run)."""
    return record.get("u_err")
