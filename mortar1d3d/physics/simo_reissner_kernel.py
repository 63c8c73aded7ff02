"""Element kernel of the Simo–Reissner beam ``herm2line3``: Hermite centreline, three-node triads.

Per element (η ∈ [-1, 1], reference arc length s, ``ds = J dη``, ``J = |r0'(η)|``):

- centreline ``r(η) = H1 r1 + H2 t1 + H3 r2 + H4 t2`` (:mod:`mortar1d3d.elements.beam.hermite`),
  nodal tangents free vectors in the current configuration;
- triads Λ_k (columns g1, g2, g3) at three nodes in ``line3`` order (0: η = -1, 1: η = +1,
  2: η = 0), interpolated objectively and path-independently (Crisfield & Jelenić, Proc R Soc A
  455, 1999): reference triad ``Λ_r = Λ_2``, local rotation vectors ``ψ_k = log(Λ_rᵀ Λ_k)``,
  ``ψ(η) = Σ_k L_k(η) ψ_k`` with the quadratic Lagrange functions, ``Λ(η) = Λ_r exp(ψ(η))``;
- strains ``Γ = Λᵀ r_s - E1`` and ``K = T(ψ)ᵀ ψ_s`` (``Λᵀ Λ_s = [K]×``, :mod:`.rotations`),
  minus their reference values Γ0, K0 at the same Gauss point (a curved reference is stress-free);
- section law in the material frame ``F = C_F (Γ - Γ0)``, ``M = C_M (K - K0)`` with diagonal
  ``C_F = diag(EA, GA2, GA3)``, ``C_M = diag(GI_T, EI2, EI3)``; energy
  ``Π_e = Σ_g ½ [wF (Γ-Γ0)·F + wM (K-K0)·M]`` with weights ``w_g J_g`` per term.

Unknowns per element (21): ``[r1, t1, r2, t2]`` (12, additive), then the spatial spin increments
``θ_0, θ_1, θ_2`` of the three triads (9, multiplicative ``Λ_k ← exp(Δθ_k) Λ_k``). The residual is
the internal virtual work in these variations,

- ``δΓ = Λᵀ (δr_s + r_s × δθ(η))``, ``δK = Λᵀ δθ_s`` with the spin field
  ``δθ(η) = δθ_r + Λ_r T(ψ) δψ(η)``, ``δψ(η) = Σ L_k δψ_k``,
  ``δψ_k = T(ψ_k)⁻¹ Λ_rᵀ (δθ_k - δθ_r)`` and ``δθ_r = δθ_2``; so
  ``δK = exp(-ψ) dT[ψ_s] δψ + T(ψ)ᵀ δψ_s``.

Per element, :data:`LAGRANGE` virtual spins replace that spin field in the spin rows by
``δθ(η) = Σ L_k δθ_k`` (4C's ``BEAM3R``): the rows of node k are ``Σ_g [L_k (n × r_s) + L_k,s m]``
with the weights ``w_g J_g`` (the centreline rows are the same).

The tangent is the derivative of that residual with respect to the 21 unknowns, triads perturbed
multiplicatively like the Newton update. Its 9 rotation columns are computed by the *complex
step*: column j is ``Im r(q ⊕ i h e_j) / h`` with ``h = 1e-30``, exact to round-off (no
subtraction), from the residual's own code compiled for complex128 (every rotation map is
complex-analytic, see :mod:`.rotations`): 9 residual evaluations in complex arithmetic per
element. Its 12 centreline columns are written out (the centreline enters through ``r_s`` in the
force term only, see :func:`_centreline_columns`); the tests check both against central
differences. It is not symmetric away from equilibrium (multiplicative rotations).

Elements are evaluated in chunks of :data:`~mortar1d3d._config.CHUNK` (in parallel when there are
several), each into its own slice by the same serial code: results are bit-identical for any
number of threads.
"""
import math

import numpy as np

from .._config import CHUNK, njit, njit_inline
from .._parallel import in_parallel
from .rotations import _cross, exp, jacobian, jacobian_derivative_transpose, jacobian_inverse, log

__all__ = ["element_range", "element_chunks", "strain_range", "N_DOFS", "STEP", "OK", "ROTATION_RANGE",
           "NOT_FINITE", "MAX_RELATIVE_ROTATION", "EXACT", "LAGRANGE"]

#: unknowns per element: 12 centreline coefficients, 3 × 3 triad spins
N_DOFS = 21
#: complex step of the tangent
STEP = 1e-30
#: status per element
OK, ROTATION_RANGE, NOT_FINITE = 0, 1, 2
#: virtual spins of the spin rows per element: the exact variation of the interpolated triads
#: (``δθ(η) = Σ Ĩ_k δθ_k``, the residual is the energy's gradient), or the spins interpolated with
#: the line3 Lagrange functions (``δθ(η) = Σ L_k δθ_k``, Jelenić & Crisfield 1999, eq. (4.3): 4C's
#: ``BEAM3R``; the same residual while the element's triads turn about one common axis)
EXACT, LAGRANGE = 0, 1
#: largest rotation of an end triad relative to the middle one that the interpolation accepts (rad):
#: the local rotation vectors ψ_k = log(Λ_rᵀ Λ_k) jump at π
MAX_RELATIVE_ROTATION = 0.99 * math.pi


@njit
def _matmul(A, B, C):
    """C = A B (3 × 3)."""
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit
def _matvec(A, x, y):
    for i in range(3):
        y[i] = A[i, 0] * x[0] + A[i, 1] * x[1] + A[i, 2] * x[2]


@njit
def _matvec_t(A, x, y):
    for i in range(3):
        y[i] = A[0, i] * x[0] + A[1, i] * x[1] + A[2, i] * x[2]


@njit
def element_setup(triads, psi_nodes, work):
    """Local rotation vectors ``ψ_k = log(Λ_2ᵀ Λ_k)`` of one element's triads (3, 3, 3) into
    ``psi_nodes`` (3, 3) (row 2 zero); returns the element status (:data:`ROTATION_RANGE` when an end
    triad is turned by more than :data:`MAX_RELATIVE_ROTATION` against the middle one).
    ``work``: (3, 3) scratch."""
    status = OK
    limit = MAX_RELATIVE_ROTATION * MAX_RELATIVE_ROTATION
    for k in range(2):
        for i in range(3):
            for j in range(3):
                work[i, j] = triads[2, 0, i] * triads[k, 0, j] + triads[2, 1, i] * triads[k, 1, j] \
                    + triads[2, 2, i] * triads[k, 2, j]
        log(work, psi_nodes[k])
        p = psi_nodes[k]
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).real > limit:
            status = ROTATION_RANGE
    for i in range(3):
        psi_nodes[2, i] = 0.0 * psi_nodes[0, 0]
    return status


@njit
def point_kinematics(Lr, psi_nodes, lag, dlag, J, rp, psi, dpsi, E, Lam, T, Gam, Kap):
    """Triad and strains at one point from the element's reference triad ``Lr`` and ``psi_nodes``.

    Parameters
    ----------
    lag, dlag : (3,) float64
        Lagrange functions and their η-derivatives at the point (line3 order).
    J : float
        ``|r0'|`` at the point.
    rp : (3,)
        Current ``r'`` (η-derivative).

    Outputs (same type as the inputs): ``psi``, ``dpsi = ψ_s`` (3,), ``E = exp(ψ)``,
    ``Lam = Λ_r E``, ``T = T(ψ)`` (3, 3), total strains ``Gam = Λᵀ r_s - E1`` and
    ``Kap = Tᵀ ψ_s`` (3,).
    """
    for i in range(3):
        psi[i] = lag[0] * psi_nodes[0, i] + lag[1] * psi_nodes[1, i]
        dpsi[i] = (dlag[0] * psi_nodes[0, i] + dlag[1] * psi_nodes[1, i]) / J
    exp(psi, E)
    _matmul(Lr, E, Lam)
    jacobian(psi, T)
    for i in range(3):
        Gam[i] = (Lam[0, i] * rp[0] + Lam[1, i] * rp[1] + Lam[2, i] * rp[2]) / J
    Gam[0] -= 1.0
    _matvec_t(T, dpsi, Kap)


@njit
def _current_point(e, g, dH, lag, dlag, A0, J, D, Lr, psi_nodes, rp, psi, dpsi, E, Lam, T, Gam, Kap):
    """:func:`point_kinematics` at Gauss point g of element e with the current
    ``r' = r0' + Σ dH_k D_k`` (into ``rp``) from the coefficients' displacement D (4, 3)."""
    for i in range(3):
        rp[i] = A0[e, g, i] + dH[e, g, 0] * D[0, i] + dH[e, g, 1] * D[1, i] + dH[e, g, 2] * D[2, i] \
            + dH[e, g, 3] * D[3, i]
    point_kinematics(Lr, psi_nodes, lag[g], dlag[g], J[e, g], rp, psi, dpsi, E, Lam, T, Gam, Kap)


@njit_inline
def _no_force_weight(wF, e, g):
    # every contribution of point g to the force term is scaled by these weights
    return wF[e, g, 0] == 0.0 and wF[e, g, 1] == 0.0 and wF[e, g, 2] == 0.0


@njit
def _residual(e, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, D, triads, want, lagrange, res, m33, v3, work):
    """Energy and (``want >= 1``) the residual ``res`` (21,) of element ``e`` at the coefficients'
    displacement ``D`` (4, 3) and the triads (3, 3, 3); returns (energy, status).

    ``lagrange``: the spin rows with :data:`LAGRANGE` virtual spins instead of the exact variation.
    ``m33``: (8, 3, 3), ``v3``: (24, 3) and ``work``: (9,) scratch of the type of ``D``.
    """
    psi_nodes = v3[0:3]
    Tinv0 = m33[0]
    Tinv1 = m33[1]
    E = m33[2]
    Lam = m33[3]
    T = m33[4]
    psi, dpsi, rp, Gam, Kap = v3[3], v3[4], v3[5], v3[6], v3[7]
    n, nxr, y, z, fpsi, fpsis = v3[8], v3[9], v3[10], v3[11], v3[12], v3[13]
    fp0, fp1, fth = v3[14], v3[15], v3[16]
    Lr = triads[2]
    status = element_setup(triads, psi_nodes, m33[5])
    energy = 0.0 * D[0, 0]
    if want >= 1:
        jacobian_inverse(psi_nodes[0], Tinv0)
        jacobian_inverse(psi_nodes[1], Tinv1)
        for i in range(N_DOFS):
            res[i] = 0.0 * D[0, 0]
        for i in range(3):
            fp0[i] = 0.0 * D[0, 0]
            fp1[i] = 0.0 * D[0, 0]
            fth[i] = 0.0 * D[0, 0]
    n_g = lag.shape[0]
    for g in range(n_g):
        if wM[e, g] == 0.0 and _no_force_weight(wF, e, g):
            continue        # a point of another element's rule (mixed force rules): contributes nothing
        Jg = J[e, g]
        _current_point(e, g, dH, lag, dlag, A0, J, D, Lr, psi_nodes, rp, psi, dpsi, E, Lam, T, Gam, Kap)
        for i in range(3):
            Gam[i] -= Gamma0[e, g, i]
            Kap[i] -= K0[e, g, i]
        wm = wM[e, g]
        for i in range(3):
            energy += 0.5 * (wF[e, g, i] * CF[e, i] * Gam[i] * Gam[i] + wm * CM[e, i] * Kap[i] * Kap[i])
        if want == 0:
            continue
        # material resultants F = C_F Γ, M = C_M K (Gam, Kap now hold them times the weights)
        for i in range(3):
            Gam[i] *= wF[e, g, i] * CF[e, i]
            Kap[i] *= wm * CM[e, i]
        _matvec(Lam, Gam, n)                     # w n (spatial force)
        for k in range(4):
            c = dH[e, g, k] / Jg
            for i in range(3):
                res[3 * k + i] += c * n[i]
        for i in range(3):
            rp[i] /= Jg                          # r_s
        _cross(n, rp, nxr)
        if lagrange:
            # δθ(η) = Σ L_k δθ_k: the spin rows are Σ_g [L_k (n × r_s) + L_k,s m] w_g J_g
            _matvec(Lam, Kap, y)                 # w m (spatial moment)
            for k in range(3):
                for i in range(3):
                    res[12 + 3 * k + i] += lag[g, k] * nxr[i] + dlag[g, k] / Jg * y[i]
            continue
        for i in range(3):
            fth[i] += nxr[i]                     # δθ_r directly
        _matvec_t(Lr, nxr, y)
        _matvec_t(T, y, fpsi)                    # Tᵀ Λ_rᵀ (n × r_s)
        _matvec(E, Kap, y)                       # exp(ψ) M
        jacobian_derivative_transpose(psi, dpsi, y, z, work)
        _matvec(T, Kap, fpsis)                   # T M, conjugate to δψ_s
        for i in range(3):
            fpsi[i] += z[i]
            fp0[i] += lag[g, 0] * fpsi[i] + dlag[g, 0] / Jg * fpsis[i]
            fp1[i] += lag[g, 1] * fpsi[i] + dlag[g, 1] / Jg * fpsis[i]
    if want == 0 or lagrange:
        return energy, status
    # δψ_k = T_k⁻¹ Λ_rᵀ (δθ_k - δθ_r): the conjugate of δθ_k is Λ_r T_k⁻ᵀ f_ψk
    _matvec_t(Tinv0, fp0, y)
    _matvec(Lr, y, z)
    _matvec_t(Tinv1, fp1, y)
    _matvec(Lr, y, n)
    for i in range(3):
        res[12 + i] = z[i]
        res[15 + i] = n[i]
        res[18 + i] = fth[i] - z[i] - n[i]
    return energy, status


@njit
def element_range(first, last, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd, triads, spins, want, energy,
                  fe, ke, status):
    """Energy, residual and tangent of elements ``first`` ... ``last - 1``.

    Parameters
    ----------
    dH : (n_el, n_g, 4) float64
        η-derivatives of the Hermite functions at the Gauss points (reference L).
    lag, dlag : (n_g, 3) float64
        Quadratic Lagrange functions (line3 order) and their η-derivatives at the points.
    A0 : (n_el, n_g, 3) float64
        Reference ``r0'`` at the points, from coefficients relative to each element's first node.
    J : (n_el, n_g) float64
        ``|r0'|``.
    wF : (n_el, n_g, 3) float64
        Integration weights ``w_g J_g`` of the force term per strain component (Γ1, Γ2, Γ3) at each
        point (a component may use its own rule: weight 0 at the points of the others).
    wM : (n_el, n_g) float64
        Integration weights ``w_g J_g`` of the moment (K) term.
    Gamma0, K0 : (n_el, n_g, 3) float64
        Reference strains at the points.
    CF, CM : (n_el, 3) float64
        ``(EA, GA2, GA3)`` and ``(GI_T, EI2, EI3)``.
    Dd : (n_el, 4, 3) float64
        Displacement of the coefficients ``(r1, t1, r2, t2)``.
    triads : (n_el, 3, 3, 3) float64
        Current nodal triads per element in line3 order (columns g1, g2, g3).
    spins : (n_el,) int64
        Virtual spins of the spin rows per element: :data:`EXACT` or :data:`LAGRANGE`.
    want : int
        0 energy, 1 and residual, 2 and tangent.
    energy : (n_el,) float64
    fe : (n_el, 21) float64
    ke : (n_el, 21, 21) float64
        ``ke[e, i, j] = ∂fe_i / ∂q_j``; not symmetric.
    status : (n_el,) int64
        :data:`OK`, :data:`ROTATION_RANGE` or :data:`NOT_FINITE`.
    """
    m33 = np.empty((8, 3, 3), dtype=np.complex128)
    v3 = np.empty((24, 3), dtype=np.complex128)
    res = np.empty(N_DOFS, dtype=np.complex128)
    Lc = np.empty((3, 3, 3), dtype=np.complex128)
    Dc = np.empty((4, 3), dtype=np.complex128)
    rot = np.empty((3, 3), dtype=np.complex128)
    spin = np.empty(3, dtype=np.complex128)
    work = np.empty(9, dtype=np.complex128)
    # the unperturbed residual and the centreline columns in real arithmetic
    r33 = np.empty((8, 3, 3))
    rv3 = np.empty((24, 3))
    rres = np.empty(N_DOFS)
    rwork = np.empty(9)
    acc = np.empty((3, 12, 3))
    for e in range(first, last):
        lagrange = spins[e] == LAGRANGE
        W, st = _residual(e, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd[e], triads[e], want, lagrange, rres,
                          r33, rv3, rwork)
        energy[e] = W
        if not math.isfinite(W):
            st = NOT_FINITE
        if want >= 1:
            for i in range(N_DOFS):
                fe[e, i] = rres[i]
                if not math.isfinite(rres[i]):
                    st = NOT_FINITE
        status[e] = st
        if want < 2:
            continue
        _centreline_columns(e, dH, lag, dlag, A0, J, wF, Gamma0, CF, Dd[e], triads[e], lagrange, ke, r33, rv3, acc)
        # rotation columns: complex step of the residual, triad k turned by exp(i h e_c)
        for i in range(4):
            for l in range(3):
                Dc[i, l] = Dd[e, i, l]
        for j in range(12, N_DOFS):
            for k in range(3):
                for i in range(3):
                    for l in range(3):
                        Lc[k, i, l] = triads[e, k, i, l]
            node = (j - 12) // 3
            for i in range(3):
                spin[i] = 0.0
            spin[(j - 12) % 3] = 1j * STEP
            exp(spin, rot)
            for i in range(3):
                for l in range(3):
                    m33[7, i, l] = Lc[node, i, l]
            _matmul(rot, m33[7], Lc[node])
            _residual(e, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dc, Lc, 1, lagrange, res, m33, v3, work)
            for i in range(N_DOFS):
                ke[e, i, j] = res[i].imag / STEP


@njit
def _centreline_columns(e, dH, lag, dlag, A0, J, wF, Gamma0, CF, D, triads, lagrange, ke, m33, v3, acc):
    """Columns 0-11 of the tangent (derivatives along the centreline coefficients), written out.

    The centreline enters the residual only through ``r_s``, in the force term: with
    ``S = Λ diag(w C_F) Λᵀ`` and ``δr_s = dH_k/J e_c``, ``δn = S δr_s``, the centreline rows get
    ``dH_l/J δn``, and the spin rows get ``δ(n × r_s) = δn × r_s + n × δr_s`` through the same
    transformation as the residual (``δθ_r`` directly, ``Tᵀ Λ_rᵀ`` for the local rotation vectors;
    with ``lagrange`` virtual spins, ``L_k`` on the spin rows of node k).
    ``acc``: (3, 12, 3) scratch (accumulators of δθ_r, δψ_0, δψ_1 per column).
    """
    psi_nodes = v3[0:3]
    Lr = triads[2]
    E, Lam, T, S, Tinv = m33[2], m33[3], m33[4], m33[5], m33[6]
    psi, dpsi, rp, Gam, Kap = v3[3], v3[4], v3[5], v3[6], v3[7]
    n, dn, dnxr, y, z, drs = v3[8], v3[9], v3[10], v3[11], v3[12], v3[13]
    element_setup(triads, psi_nodes, m33[0])
    for col in range(12):
        for l in range(N_DOFS):
            ke[e, l, col] = 0.0
        for i in range(3):
            acc[0, col, i] = 0.0
            acc[1, col, i] = 0.0
            acc[2, col, i] = 0.0
    for g in range(lag.shape[0]):
        if _no_force_weight(wF, e, g):
            continue        # a moment-only point: the centreline columns get nothing from it
        Jg = J[e, g]
        _current_point(e, g, dH, lag, dlag, A0, J, D, Lr, psi_nodes, rp, psi, dpsi, E, Lam, T, Gam, Kap)
        for i in range(3):
            Gam[i] = (Gam[i] - Gamma0[e, g, i]) * wF[e, g, i] * CF[e, i]
            rp[i] /= Jg
        _matvec(Lam, Gam, n)
        for i in range(3):
            for l in range(3):
                S[i, l] = Lam[i, 0] * wF[e, g, 0] * CF[e, 0] * Lam[l, 0] \
                    + Lam[i, 1] * wF[e, g, 1] * CF[e, 1] * Lam[l, 1] + Lam[i, 2] * wF[e, g, 2] * CF[e, 2] * Lam[l, 2]
        for k in range(4):
            ck = dH[e, g, k] / Jg
            for c in range(3):
                col = 3 * k + c
                for i in range(3):
                    dn[i] = S[i, c] * ck
                    drs[i] = 0.0
                drs[c] = ck
                for m in range(4):
                    cm = dH[e, g, m] / Jg
                    for i in range(3):
                        ke[e, 3 * m + i, col] += cm * dn[i]
                _cross(dn, rp, dnxr)
                _cross(n, drs, y)
                if lagrange:
                    for k2 in range(3):
                        for i in range(3):
                            ke[e, 12 + 3 * k2 + i, col] += lag[g, k2] * (dnxr[i] + y[i])
                    continue
                for i in range(3):
                    dnxr[i] += y[i]
                    acc[0, col, i] += dnxr[i]
                _matvec_t(Lr, dnxr, y)
                _matvec_t(T, y, z)
                for i in range(3):
                    acc[1, col, i] += lag[g, 0] * z[i]
                    acc[2, col, i] += lag[g, 1] * z[i]
    if lagrange:
        return
    for k in range(2):
        jacobian_inverse(psi_nodes[k], Tinv)
        for col in range(12):
            _matvec_t(Tinv, acc[1 + k, col], y)
            _matvec(Lr, y, z)
            for i in range(3):
                ke[e, 12 + 3 * k + i, col] = z[i]
                ke[e, 18 + i, col] -= z[i]
    for col in range(12):
        for i in range(3):
            ke[e, 18 + i, col] += acc[0, col, i]


@njit
def element_chunks(dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd, triads, spins, want, energy, fe, ke, status):
    """:func:`element_range` over chunks of :data:`CHUNK` elements in parallel (bit-identical for any
    number of threads: every element is computed by the same serial code)."""
    n_el = dH.shape[0]
    _element_chunks_workers((n_el + CHUNK - 1) // CHUNK, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd, triads,
                           spins, want, energy, fe, ke, status, n_el)


@njit
def _element_chunks_worker(c, dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd, triads, spins, want, energy, fe,
                          ke, status, n_el):
    element_range(c * CHUNK, min(n_el, (c + 1) * CHUNK), dH, lag, dlag, A0, J, wF, wM, Gamma0, K0, CF, CM, Dd,
                  triads, spins, want, energy, fe, ke, status)


_element_chunks_workers = in_parallel(_element_chunks_worker)


@njit
def strain_range(dH, lag, dlag, A0, J, Dd, triads, Gamma, Kappa, Lambda, status):
    """Total strains ``Γ``, ``K`` (n_el, n_p, 3) and triads ``Λ`` (n_el, n_p, 3, 3) at points given by
    the tables (shapes as in :func:`element_range`, n_p points), in float64; ``status`` (n_el,)."""
    psi_nodes = np.empty((3, 3))
    work = np.empty((3, 3))
    psi = np.empty(3)
    dpsi = np.empty(3)
    rp = np.empty(3)
    E = np.empty((3, 3))
    T = np.empty((3, 3))
    for e in range(dH.shape[0]):
        status[e] = element_setup(triads[e], psi_nodes, work)
        for g in range(lag.shape[0]):
            _current_point(e, g, dH, lag, dlag, A0, J, Dd[e], triads[e, 2], psi_nodes, rp, psi, dpsi, E, Lambda[e, g],
                           T, Gamma[e, g], Kappa[e, g])
