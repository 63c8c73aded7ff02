"""Numba kernels of the rational basis of one NURBS element, two ways.

*Bézier form* (what the engine uses): after Bézier extraction (:func:`mortar1d3d.nurbs.knots.extraction_operators`)
an element is a rational Bernstein element on [-1, 1]³ with its own (p0+1)(p1+1)(p2+1) control points
and weights, ``R_a = w_a B_a / W`` with ``W = Σ_b w_b B_b`` and B_a the tensor-product Bernstein
polynomials. Functions are numbered ``a = (i (p1+1) + j) (p2+1) + k`` (the last direction fastest,
as a C-order ``(p0+1, p1+1, p2+1)`` array).

*Element-local knots* (Cox–de Boor): the p+1 B-splines non-zero on a span from the 2p knots around it,
times the global control weights. Kept for the measurement that chose the Bézier form
(``benchmarks/nurbs_basis.py``) and as an independent check in the tests.
"""
import numpy as np

from .._config import njit
from ..elements.solid.bezier_hex import bernstein
from ..elements.solid.dispatch import _quotient_rule


@njit
def _rational_tensor(p0, p1, p2, v, dv, weights, R, dR):
    """R_a = w_a B_a / W and its derivatives from the 1D values ``v`` and derivatives ``dv`` (3, 8) of
    any tensor-product basis; returns W (the quotient rule is the solid elements' own,
    :func:`mortar1d3d.elements.solid.dispatch._quotient_rule`)."""
    a = 0
    for i in range(p0 + 1):
        for j in range(p1 + 1):
            for k in range(p2 + 1):
                w = weights[a]
                R[a] = w * v[0, i] * v[1, j] * v[2, k]
                dR[a, 0] = w * dv[0, i] * v[1, j] * v[2, k]
                dR[a, 1] = w * v[0, i] * dv[1, j] * v[2, k]
                dR[a, 2] = w * v[0, i] * v[1, j] * dv[2, k]
                a += 1
    return _quotient_rule(a, R, dR)


@njit
def rational_bernstein(p0, p1, p2, xi, weights, R, dR):
    """Rational tensor Bernstein basis R_a (and ∂R_a/∂ξ_d) of one element at ``xi`` (3,).

    ``weights`` (n,) are the element's Bézier weights (n = (p0+1)(p1+1)(p2+1)); writes ``R[:n]``
    and ``dR[:n, :3]``. Returns W(ξ) = Σ w_a B_a (> 0 inside an element with positive weights).
    """
    v = np.empty((3, 8))
    dv = np.empty((3, 8))
    bernstein(p0, xi[0], v[0], dv[0])
    bernstein(p1, xi[1], v[1], dv[1])
    bernstein(p2, xi[2], v[2], dv[2])
    return _rational_tensor(p0, p1, p2, v, dv, weights, R, dR)


@njit
def local_bsplines(p, knots, x, v, dv):
    """The p+1 B-splines non-zero on one span from its 2p local knots, at ``x`` ∈ [-1, 1] of the span.

    ``knots`` (2p,) are ``U[k-p+1 … k+p]`` of span k = [U[k], U[k+1]] (so the span is
    ``[knots[p-1], knots[p]]``); writes ``v[:p+1]`` and d/dx into ``dv[:p+1]``. Cox–de Boor's
    recursion on the local knots.
    """
    lo = knots[p - 1]
    hi = knots[p]
    u = lo + 0.5 * (1.0 + x) * (hi - lo)
    v[0] = 1.0
    for q in range(1, p + 1):
        if q == p:
            for a in range(p + 1):
                left = v[a - 1] / (knots[a + p - 1] - knots[a - 1]) if a >= 1 else 0.0
                right = v[a] / (knots[a + p] - knots[a]) if a < p else 0.0
                dv[a] = p * (left - right) * 0.5 * (hi - lo)
        # functions of degree q on the span: indices 0..q, local knot index offset p - q
        saved = 0.0
        for a in range(q):
            i0 = p - q + a            # knots of function a of degree q: knots[i0 .. i0+q+1] shifted
            right_knot = knots[i0 + q]
            left_knot = knots[i0]
            temp = v[a] / (right_knot - left_knot)
            v[a] = saved + (right_knot - u) * temp
            saved = (u - left_knot) * temp
        v[q] = saved


@njit
def rational_local(p0, p1, p2, xi, k0, k1, k2, weights, R, dR):
    """Rational basis of one NURBS element from its local knots ``k0, k1, k2`` (2p_d each) and the
    global control weights of its (p0+1)(p1+1)(p2+1) functions, in the order of
    :func:`rational_bernstein`; returns W(ξ)."""
    v = np.empty((3, 8))
    dv = np.empty((3, 8))
    local_bsplines(p0, k0, xi[0], v[0], dv[0])
    local_bsplines(p1, k1, xi[1], v[1], dv[1])
    local_bsplines(p2, k2, xi[2], v[2], dv[2])
    return _rational_tensor(p0, p1, p2, v, dv, weights, R, dR)


@njit
def evaluate_bezier(p0, p1, p2, control, weights, xi, x, status):
    """Points x(ξ) = Σ R_a P_a of Bézier elements: ``control`` (m, n, 3), ``weights`` (m, n),
    ``xi`` (m, q, 3) → ``x`` (m, q, 3); ``status[e]`` 1 where W <= 0 somewhere (invalid weights)."""
    n = (p0 + 1) * (p1 + 1) * (p2 + 1)
    R = np.empty(n)
    dR = np.empty((n, 3))
    for e in range(control.shape[0]):
        status[e] = 0
        for q in range(xi.shape[1]):
            W = rational_bernstein(p0, p1, p2, xi[e, q], weights[e], R, dR)
            if not W > 0.0:
                status[e] = 1
            for i in range(3):
                s = 0.0
                for a in range(n):
                    s += R[a] * control[e, a, i]
                x[e, q, i] = s


__all__ = ["bernstein", "rational_bernstein", "local_bsplines", "rational_local", "evaluate_bezier"]
