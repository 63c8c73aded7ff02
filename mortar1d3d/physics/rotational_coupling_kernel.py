"""Point kernels of the rotational beam-to-solid coupling (Numba, float64 or complex128).

At an integration point of the beam centreline (beam element e, parameter η; solid element s,
parameter ξ) the coupling compares two triads (Steinbrecher, Popp & Meier, Comput Mech 2022):

- the beam's cross-section triad Λ_B(η), interpolated from the element's three nodal triads
  exactly as the Simo–Reissner element does (:func:`.simo_reissner_kernel.element_setup`,
  ``Λ_B = Λ_2 exp(Σ L_k ψ_k)``);
- a solid triad Λ_S built from the solid's deformation gradient ``F = Σ_a x_a ⊗ G_a`` at ξ
  (``G_a = J0⁻ᵀ ∂N_a/∂ξ``, the reference gradients of the shape functions) and the point's
  reference triad Λ_S0 (taken equal to the beam's reference triad there):

  ``POLAR``
      ``Λ_S = R Λ_S0`` with the rotation R of the polar decomposition ``F = R U``, by Newton's
      iteration ``R ← ½ (R + R⁻ᵀ)`` (quadratic convergence; each step is an analytic map, so a
      complex step passes through it).
  ``DEFORMATION_GRADIENT``
      From the deformed reference base vectors ``a_i = F g_i0``: ``e1 = a1/|a1|``; the parts of
      a2 and a3 normal to e1 give two candidate directions of the second base vector, ``b2`` (a2's)
      and ``b3 × e1`` (a3's, turned back by a quarter turn about e1), each the second base vector
      of a Gram–Schmidt triad (from a1, a2 and from a1, a3 respectively); ``e2`` is their
      normalised mean (the mean of the two triads, which share e1), ``e3 = e1 × e2``. No base
      vector of the section is preferred, and a rigid rotation Q of the solid (``F → Q F``)
      turns every a_i and so the triad.

The constraint measure is the spatial relative rotation vector ``ψ = log(Λ_B Λ_Sᵀ)``: zero in the
reference configuration (``Λ_S0 = Λ_B0``), turned with any rigid rotation of the whole scene (its
norm, which the penalty energy sees, unchanged).

Derivatives. The local unknowns of a point are the solid element's nodal displacements (3 per
node, additive) and the spatial spins of the beam element's three triads (multiplicative, ``Λ_k ←
exp(Δθ_k) Λ_k``, like the Newton update of the beam). :func:`point_jacobian` returns ψ and
``J = ∂ψ/∂(u, θ)`` by the complex step (every map above is complex-analytic). The second
derivative ``∂(Jᵀλ)/∂(u, θ)`` for a fixed λ (the geometric part of the tangent,
:func:`point_hessian`) is the central difference of these exact gradients: truncation ``O(h²)``
and round-off ``eps/h`` are both about 1e-10 relative with ``h`` = :data:`FD_STEP`.
"""
import numpy as np

from .._config import njit
from ..elements.solid import dispatch as solid_types
from .rotations import exp, log
from .simo_reissner_kernel import _matmul, element_setup

__all__ = ["POLAR", "DEFORMATION_GRADIENT", "TRIADS", "point_psi", "point_jacobian", "point_hessian",
           "reference_gradients", "OK", "NOT_CONVERGED", "STEP", "FD_STEP"]

POLAR, DEFORMATION_GRADIENT = 0, 1
#: triad names of the scene (``coupling.rotational.triad``) → kernel codes
TRIADS = {"polar": POLAR, "deformation_gradient": DEFORMATION_GRADIENT}
OK, NOT_CONVERGED = 0, 1
#: complex step of the Jacobian
STEP = 1e-30
#: central-difference step of the geometric tangent: radians for spins, times the element size for
#: positions
FD_STEP = 1e-5
#: Newton iterations of the polar decomposition: stop when the real part changes by less than this
#: (relative), then iterate twice more so that a complex perturbation converges too
POLAR_TOL = 1e-14
POLAR_MAX_ITERATIONS = 60


@njit
def reference_gradients(codes, conn, X, solid_element, xi, G, nodes, n_local):
    """Reference gradients ``G[p, a] = ∂N_a/∂X`` (n_pts, MAX_NODES, 3) of the solid shape functions
    at every point p (solid element ``solid_element[p]``, parameter ``xi[p]``), its node ids
    ``nodes[p, a]`` and node count ``n_local[p]``."""
    dN = np.empty((solid_types.MAX_NODES, 3))
    J0 = np.empty((3, 3))
    Ji = np.empty((3, 3))
    for p in range(len(solid_element)):
        s = solid_element[p]
        code = codes[s]
        n = solid_types.N_NODES[code]
        solid_types.deriv(code, xi[p], dN)
        for i in range(3):
            for j in range(3):
                acc = 0.0
                for a in range(n):
                    acc += X[conn[s, a], i] * dN[a, j]
                J0[i, j] = acc
        _inverse3(J0, Ji)
        for a in range(n):
            nodes[p, a] = conn[s, a]
            for j in range(3):
                G[p, a, j] = dN[a, 0] * Ji[0, j] + dN[a, 1] * Ji[1, j] + dN[a, 2] * Ji[2, j]
        n_local[p] = n


@njit
def _inverse3(A, B):
    """B = A⁻¹ (3 × 3) by cofactors (analytic, complex-safe)."""
    c00 = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    c01 = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    c02 = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    det = A[0, 0] * c00 + A[0, 1] * c01 + A[0, 2] * c02
    B[0, 0] = c00 / det
    B[1, 0] = c01 / det
    B[2, 0] = c02 / det
    B[0, 1] = (A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]) / det
    B[1, 1] = (A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]) / det
    B[2, 1] = (A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]) / det
    B[0, 2] = (A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]) / det
    B[1, 2] = (A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]) / det
    B[2, 2] = (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]) / det


@njit
def _unit(v):
    s = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])      # no conjugate: complex-analytic
    v[0] /= s
    v[1] /= s
    v[2] /= s


@njit
def polar_rotation(F, R, work):
    """Rotation R of the polar decomposition ``F = R U`` (det F > 0) by ``R ← ½ (R + R⁻ᵀ)``.
    ``work``: (2, 3, 3) scratch. Returns OK or NOT_CONVERGED."""
    for i in range(3):
        for j in range(3):
            R[i, j] = F[i, j]
    extra = 0
    for _ in range(POLAR_MAX_ITERATIONS):
        _inverse3(R, work[0])
        change = 0.0
        for i in range(3):
            for j in range(3):
                new = 0.5 * (R[i, j] + work[0, j, i])
                change = max(change, abs((new - R[i, j]).real))
                R[i, j] = new
        if change < POLAR_TOL:
            extra += 1
            if extra > 2:
                return OK
    return NOT_CONVERGED


@njit
def solid_triad(kind, F, L0, L, work):
    """Solid triad ``L`` (3, 3) of type ``kind`` from F and the reference triad ``L0`` (real).
    ``work``: (4, 3, 3) scratch. Returns a status."""
    status = OK
    if kind == POLAR:
        status = polar_rotation(F, work[2], work[:2])
        _matmul(work[2], L0.astype(F.dtype), L)
        return status
    a = work[0]
    for i in range(3):
        for k in range(3):
            a[i, k] = F[i, 0] * L0[0, k] + F[i, 1] * L0[1, k] + F[i, 2] * L0[2, k]
    e1 = work[1, 0]
    b2 = work[1, 1]
    b3 = work[1, 2]
    for i in range(3):
        e1[i] = a[i, 0]
    _unit(e1)
    p2 = a[0, 1] * e1[0] + a[1, 1] * e1[1] + a[2, 1] * e1[2]
    p3 = a[0, 2] * e1[0] + a[1, 2] * e1[1] + a[2, 2] * e1[2]
    for i in range(3):
        b2[i] = a[i, 1] - p2 * e1[i]
        b3[i] = a[i, 2] - p3 * e1[i]
    _unit(b2)
    _unit(b3)
    c = work[2, 0]
    c[0] = b3[1] * e1[2] - b3[2] * e1[1]        # b3 × e1: a3's candidate for the second base vector
    c[1] = b3[2] * e1[0] - b3[0] * e1[2]
    c[2] = b3[0] * e1[1] - b3[1] * e1[0]
    e2 = work[2, 1]
    for i in range(3):
        e2[i] = b2[i] + c[i]
    _unit(e2)
    for i in range(3):
        L[i, 0] = e1[i]
        L[i, 1] = e2[i]
    L[0, 2] = e1[1] * e2[2] - e1[2] * e2[1]
    L[1, 2] = e1[2] * e2[0] - e1[0] * e2[2]
    L[2, 2] = e1[0] * e2[1] - e1[1] * e2[0]
    return status


@njit
def beam_triad(triads, lag, L, work):
    """Interpolated beam triad ``L`` (3, 3) at a point with Lagrange values ``lag`` (3,) from the
    element's nodal triads (3, 3, 3) in line3 order. ``work``: (4, 3, 3) scratch."""
    psi_nodes = work[0]
    status = element_setup(triads, psi_nodes, work[1])
    psi = work[2, 0]
    for i in range(3):
        psi[i] = lag[0] * psi_nodes[0, i] + lag[1] * psi_nodes[1, i]
    exp(psi, work[3])
    _matmul(triads[2], work[3], L)
    return status


@njit
def point_psi(kind, x, G, n, L0, triads, lag, psi, work):
    """ψ = log(Λ_B Λ_Sᵀ) (3,) at one point.

    Parameters
    ----------
    kind : int
        POLAR or DEFORMATION_GRADIENT.
    x : (>= n, 3)
        Current positions of the solid element's nodes.
    G : (>= n, 3) float64
        Reference gradients of the solid shape functions at the point.
    L0 : (3, 3) float64
        Reference triad of the point.
    triads : (3, 3, 3)
        Current nodal triads of the beam element (line3 order).
    lag : (3,) float64
        Line3 Lagrange functions at the point.
    work : (8, 3, 3) scratch of the type of x.
    """
    F = work[0]
    for i in range(3):
        for j in range(3):
            s = 0.0 * x[0, 0]
            for a in range(n):
                s += x[a, i] * G[a, j]
            F[i, j] = s
    LS = work[1]
    status = solid_triad(kind, F, L0, LS, work[4:8])
    LB = work[2]
    status = max(status, beam_triad(triads, lag, LB, work[4:8]))
    P = work[3]
    for i in range(3):
        for j in range(3):
            P[i, j] = LB[i, 0] * LS[j, 0] + LB[i, 1] * LS[j, 1] + LB[i, 2] * LS[j, 2]
    log(P, psi)
    return status


@njit
def _gradient(kind, x, G, n, L0, triads, lag, lam, out, cx, ct, R, psi, work):
    """``out = Jᵀ λ`` (3 n + 9,) at the state (x, triads), by the complex step; also returns ψ·λ's
    status. When ``lam`` is None-like (all three ``lam`` rows used), see :func:`point_jacobian`."""
    status = OK
    for c in range(3 * n + 9):
        for a in range(n):
            for i in range(3):
                cx[a, i] = x[a, i]
        for k in range(3):
            for i in range(3):
                for j in range(3):
                    ct[k, i, j] = triads[k, i, j]
        if c < 3 * n:
            cx[c // 3, c % 3] += 1j * STEP
        else:
            k = (c - 3 * n) // 3
            v = work[0, 0]
            v[0] = 0.0
            v[1] = 0.0
            v[2] = 0.0
            v[(c - 3 * n) % 3] = 1j * STEP
            exp(v, R)
            for i in range(3):
                for j in range(3):
                    ct[k, i, j] = R[i, 0] * triads[k, 0, j] + R[i, 1] * triads[k, 1, j] + R[i, 2] * triads[k, 2, j]
        status = max(status, point_psi(kind, cx, G, n, L0, ct, lag, psi, work))
        for i in range(lam.shape[0]):
            out[i, c] = (psi[0].imag * lam[i, 0] + psi[1].imag * lam[i, 1] + psi[2].imag * lam[i, 2]) / STEP
    return status


@njit
def point_jacobian(kind, x, G, n, L0, triads, lag, psi, J):
    """ψ (3,) and ``J = ∂ψ/∂(u, θ)`` (3, 3 n + 9) at one point (real inputs); returns a status."""
    work = np.empty((8, 3, 3), dtype=np.complex128)
    cx = np.empty((n, 3), dtype=np.complex128)
    ct = np.empty((3, 3, 3), dtype=np.complex128)
    R = np.empty((3, 3), dtype=np.complex128)
    cpsi = np.empty(3, dtype=np.complex128)
    status = _gradient(kind, x, G, n, L0, triads, lag, np.eye(3), J, cx, ct, R, cpsi, work)
    rwork = np.empty((8, 3, 3))
    status = max(status, point_psi(kind, x, G, n, L0, triads, lag, psi, rwork))
    return status


@njit
def point_hessian(kind, x, G, n, L0, triads, lag, lam, size, H):
    """``H = ∂(Jᵀλ)/∂(u, θ)`` (3 n + 9, 3 n + 9) for a fixed λ (3,): central differences (step
    ``FD_STEP × size`` for positions, ``FD_STEP`` rad for spins) of the complex-step gradients."""
    m = 3 * n + 9
    work = np.empty((8, 3, 3), dtype=np.complex128)
    cx = np.empty((n, 3), dtype=np.complex128)
    ct = np.empty((3, 3, 3), dtype=np.complex128)
    R = np.empty((3, 3), dtype=np.complex128)
    cpsi = np.empty(3, dtype=np.complex128)
    xs = np.empty((n, 3))
    ts = np.empty((3, 3, 3))
    Rr = np.empty((3, 3))
    v = np.zeros(3)
    g = np.empty((1, m))
    lam2 = lam.reshape(1, 3)
    status = OK
    for l in range(m):
        h = FD_STEP * size if l < 3 * n else FD_STEP
        for sign in (1.0, -1.0):
            xs[:, :] = x[:n]
            ts[:, :, :] = triads
            if l < 3 * n:
                xs[l // 3, l % 3] += sign * h
            else:
                k = (l - 3 * n) // 3
                v[:] = 0.0
                v[(l - 3 * n) % 3] = sign * h
                exp(v, Rr)
                for i in range(3):
                    for j in range(3):
                        ts[k, i, j] = Rr[i, 0] * triads[k, 0, j] + Rr[i, 1] * triads[k, 1, j] \
                            + Rr[i, 2] * triads[k, 2, j]
            status = max(status, _gradient(kind, xs, G, n, L0, ts, lag, lam2, g, cx, ct, R, cpsi, work))
            for c in range(m):
                H[c, l] += sign * g[0, c] / (2.0 * h)
    return status


@njit
def _point_state(p, x, nodes, n_local, triads, rotation_nodes, beam_element, xl, tl):
    n = n_local[p]
    for a in range(n):
        for i in range(3):
            xl[a, i] = x[nodes[p, a], i]
    e = beam_element[p]
    for k in range(3):
        tl[k] = triads[rotation_nodes[e, k]]
    return n


@njit
def reference_triads_at(triads0, rotation_nodes, beam_element, lag, L0, status):
    """Reference beam triads ``L0`` (n_pts, 3, 3) at the points (the solid triads' reference)."""
    work = np.empty((4, 3, 3))
    tl = np.empty((3, 3, 3))
    for p in range(len(beam_element)):
        e = beam_element[p]
        for k in range(3):
            tl[k] = triads0[rotation_nodes[e, k]]
        status[p] = beam_triad(tl, lag[p], L0[p], work)


@njit
def jacobian_range(kind, x, nodes, n_local, G, L0, triads, rotation_nodes, beam_element, lag, want, psi, J, status):
    """ψ (n_pts, 3) at every point and, when ``want``, J (n_pts, 3, 3 MAX_NODES + 9): columns
    ``0..3n-1`` the point's solid nodes (``nodes[p]``), then ``3n..3n+8`` the spins of its beam
    element's rotation nodes (line3 order); the rest left as is."""
    m = nodes.shape[1]
    xl = np.empty((m, 3))
    tl = np.empty((3, 3, 3))
    work = np.empty((8, 3, 3))
    for p in range(len(beam_element)):
        n = _point_state(p, x, nodes, n_local, triads, rotation_nodes, beam_element, xl, tl)
        if want:
            status[p] = point_jacobian(kind, xl[:n], G[p], n, L0[p], tl, lag[p], psi[p], J[p])
        else:
            status[p] = point_psi(kind, xl[:n], G[p], n, L0[p], tl, lag[p], psi[p], work)


@njit
def hessian_range(kind, x, nodes, n_local, G, L0, triads, rotation_nodes, beam_element, lag, lam, size, H, status):
    """``H[p] = ∂(J_pᵀ λ_p)/∂(u, θ)`` (n_pts, 3 MAX_NODES + 9, same) in the layout of
    :func:`jacobian_range`; H must hold zeros on entry."""
    m = nodes.shape[1]
    xl = np.empty((m, 3))
    tl = np.empty((3, 3, 3))
    for p in range(len(beam_element)):
        n = _point_state(p, x, nodes, n_local, triads, rotation_nodes, beam_element, xl, tl)
        if lam[p, 0] == 0.0 and lam[p, 1] == 0.0 and lam[p, 2] == 0.0:
            status[p] = OK
            continue
        status[p] = point_hessian(kind, xl[:n], G[p], n, L0[p], tl, lag[p], lam[p], size[p], H[p])
