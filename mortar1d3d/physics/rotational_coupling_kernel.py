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
  ``SYMMETRIC``
      All three ``a_i = F g_i0`` alike (4C's ``deformation_gradient_3d_general``): the axis
      ``d = (a1 + a2 + a3)/|…|``; the unit parts ``p_i`` of the a_i normal to d; their angles from
      p1 about d, ``θ2 = acos(p1·p2)`` and ``θ3 = 2π - acos(p1·p3)``, whose mean offset from an
      even spread is ``α = (θ2 + θ3 - 2π)/3``; the triad is the orthonormal "tripod" about d (each
      base vector at acos(1/√3) from d, as a cube's edges from its diagonal): its first vector is
      p1 tilted towards d to that angle, then turned by α about d, the others by α + 2π/3 and
      α + 4π/3. In the reference ``Λ_S = Λ_S0``; a rigid rotation turns it along.
  ``PLANE_Y``, ``PLANE_Z``, ``PLANE_AVERAGE``
      Plane problems in the y-z plane (4C's ``deformation_gradient_y_2d``, ``…_z_2d``,
      ``…_average_2d``): ``Λ_S = exp(θ e_x) Λ_S0`` with θ the angle by which F turns the global
      y axis, ``θ_y = atan2(F_zy, F_yy)``, the z axis, ``θ_z = atan2(F_zz, F_yz) − π/2``, or their
      mean. Defined for an F that keeps the y-z plane (the 4C reader checks the reference triads;
      out of the plane the triad sees only F's y-z block). The angles are evaluated by the
      half-angle form ``2 atan(y / (√(x² + y²) + x))``, complex-analytic away from ±π.
  ``LOCAL_1``, ``LOCAL_2``, ``LOCAL_3``
      One deformed base vector kept (4C's ``deformation_gradient_3d_local_k``): with
      ``a_i = F g_i0``, ``LOCAL_1`` has ``e1 = a1/|a1|``, ``e2 ∥ a3 × a1``, ``e3 = e1 × e2``;
      ``LOCAL_2`` keeps a2 (``e2 = a2/|a2|``, ``e3 ∥ a1 × a2``, ``e1 = e2 × e3``) and ``LOCAL_3``
      keeps a3 (``e3 = a3/|a3|``, ``e1 ∥ a2 × a3``, ``e2 = e3 × e1``). Each is ``Λ_S0`` in the
      reference and turns with a rigid rotation.

The constraint measure is the spatial relative rotation vector ``ψ = log(Λ_B Λ_Sᵀ)``: zero in the
reference configuration (``Λ_S0 = Λ_B0``), turned with any rigid rotation of the whole scene (its
norm, which the penalty energy sees, unchanged).

Derivatives. ψ depends on the solid only through F, so the kernels differentiate with respect to
18 local parameters: the nine entries of F and the spatial spins of the beam element's three triads
(multiplicative, ``Λ_k ← exp(Δθ_k) Λ_k``, like the Newton update of the beam); the caller chains
F to the nodal displacements with ``∂F/∂x_a = I ⊗ G_a`` (any element type, at no extra cost per
node). :func:`point_jacobian` returns ψ and ``J = ∂ψ/∂(F, θ)`` by the complex step (every map
above is complex-analytic). The second derivative ``∂(Jᵀλ)/∂(F, θ)`` for a fixed λ (the geometric
part of the tangent, :func:`point_hessian`) is the central difference of these exact gradients:
truncation ``O(h²)`` and round-off ``eps/h`` are both about 1e-10 relative with ``h`` =
:data:`FD_STEP`.
"""
import numpy as np

from .._config import njit
from .._parallel import in_parallel
from ..elements.solid import dispatch as solid_types
from .rotations import exp, log
from .simo_reissner_kernel import _matmul, element_setup

__all__ = ["POLAR", "DEFORMATION_GRADIENT", "SYMMETRIC", "PLANE_Y", "PLANE_Z", "PLANE_AVERAGE", "LOCAL_1", "LOCAL_2",
           "LOCAL_3", "TRIADS", "point_psi", "point_jacobian", "point_hessian",
           "reference_gradients", "OK", "NOT_CONVERGED", "STEP", "FD_STEP", "POINT_CHUNK"]

POLAR, DEFORMATION_GRADIENT, SYMMETRIC, PLANE_Y, PLANE_Z, PLANE_AVERAGE, LOCAL_1, LOCAL_2, LOCAL_3 = range(9)
#: triad names of the scene (``coupling.rotational.triad``) → kernel codes
TRIADS = {"polar": POLAR, "deformation_gradient": DEFORMATION_GRADIENT, "deformation_gradient_symmetric": SYMMETRIC,
          "plane_y": PLANE_Y, "plane_z": PLANE_Z, "plane_average": PLANE_AVERAGE,
          "deformation_gradient_local_1": LOCAL_1, "deformation_gradient_local_2": LOCAL_2,
          "deformation_gradient_local_3": LOCAL_3}
#: ``SYMMETRIC``: angle between the mean direction of a unit cube's edges and each edge, acos(1/√3)
_TRIPOD_ANGLE = float(np.arccos(1.0 / np.sqrt(3.0)))
OK, NOT_CONVERGED = 0, 1
#: complex step of the Jacobian
STEP = 1e-30
#: central-difference step of the geometric tangent (entries of F, and spins in radians)
FD_STEP = 1e-5
#: points per parallel chunk of :func:`hessian_range`: a point costs about a millisecond there
#: (648 complex evaluations of ψ), so small chunks keep the threads busy at no measurable overhead
POINT_CHUNK = 8
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
def _deformed_basis(F, L0, a):
    """``a = F L0`` (3, 3): the reference base vectors g_i0 (columns of L0) deformed, ``a_i = F g_i0``."""
    for i in range(3):
        for k in range(3):
            a[i, k] = F[i, 0] * L0[0, k] + F[i, 1] * L0[1, k] + F[i, 2] * L0[2, k]
    return a


@njit
def _plane_angle(y, x):
    """``atan2(y, x)`` as ``2 atan(y / (√(x² + y²) + x))``: complex-analytic (a complex step passes
    through it) for angles away from ±π."""
    return 2.0 * np.arctan(y / (np.sqrt(x * x + y * y) + x))


@njit
def _plane_triad(kind, F, L0, L):
    """``PLANE_*`` triads: ``L = exp(θ e_x) L0`` with θ from F's y-z block (module docstring)."""
    theta_y = _plane_angle(F[2, 1], F[1, 1])
    theta_z = _plane_angle(F[2, 2], F[1, 2]) - 0.5 * np.pi
    theta = theta_y if kind == PLANE_Y else theta_z if kind == PLANE_Z else 0.5 * (theta_y + theta_z)
    c, s = np.cos(theta), np.sin(theta)
    for k in range(3):
        L[0, k] = L0[0, k]
        L[1, k] = c * L0[1, k] - s * L0[2, k]
        L[2, k] = s * L0[1, k] + c * L0[2, k]


@njit
def _local_triad(kind, F, L0, L, work):
    """``LOCAL_*`` triads (module docstring): the kept deformed base vector k, the next one of the
    cyclic order normal to it and to base vector k - 1, the third completing the triad."""
    k = kind - LOCAL_1                          # the kept base vector: 0, 1, 2
    j = (k + 1) % 3                             # the one built as a cross product
    m = (k + 2) % 3
    a = _deformed_basis(F, L0, work[0])
    t0 = work[1, 0]
    t1 = work[1, 1]
    t2 = work[1, 2]
    for i in range(3):
        t0[i] = a[i, k]
    # t1 = a_m × a_k (4C: the construction vector a_m, crossed with the kept one)
    t1[0] = a[1, m] * t0[2] - a[2, m] * t0[1]
    t1[1] = a[2, m] * t0[0] - a[0, m] * t0[2]
    t1[2] = a[0, m] * t0[1] - a[1, m] * t0[0]
    t2[0] = t0[1] * t1[2] - t0[2] * t1[1]
    t2[1] = t0[2] * t1[0] - t0[0] * t1[2]
    t2[2] = t0[0] * t1[1] - t0[1] * t1[0]
    _unit(t0)
    _unit(t1)
    _unit(t2)
    for i in range(3):
        L[i, k] = t0[i]
        L[i, j] = t1[i]
        L[i, m] = t2[i]


@njit
def solid_triad(kind, F, L0, L, work):
    """Solid triad ``L`` (3, 3) of type ``kind`` from F and the reference triad ``L0`` (real).
    ``work``: (4, 3, 3) scratch. Returns a status."""
    status = OK
    if kind >= LOCAL_1:
        _local_triad(kind, F, L0, L, work)
        return status
    if kind >= PLANE_Y:
        _plane_triad(kind, F, L0, L)
        return status
    if kind == POLAR:
        status = polar_rotation(F, work[2], work[:2])
        _matmul(work[2], L0.astype(F.dtype), L)
        return status
    if kind == SYMMETRIC:
        _symmetric_triad(F, L0, L, work)
        return status
    a = _deformed_basis(F, L0, work[0])
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
def _symmetric_triad(F, L0, L, work):
    """:data:`SYMMETRIC` triad ``L`` (3, 3) from F and L0; ``work``: (4, 3, 3) scratch (every step
    complex-analytic: no conjugates, ``arccos`` of the complex argument)."""
    a = _deformed_basis(F, L0, work[0])
    d = work[1, 0]
    for i in range(3):
        d[i] = a[i, 0] + a[i, 1] + a[i, 2]
    _unit(d)
    p = work[2]                                 # rows: the unit normal parts p_i
    for k in range(3):
        c = a[0, k] * d[0] + a[1, k] * d[1] + a[2, k] * d[2]
        for i in range(3):
            p[k, i] = a[i, k] - c * d[i]
        _unit(p[k])
    c12 = p[0, 0] * p[1, 0] + p[0, 1] * p[1, 1] + p[0, 2] * p[1, 2]
    c13 = p[0, 0] * p[2, 0] + p[0, 1] * p[2, 1] + p[0, 2] * p[2, 2]
    # θ2 = acos(c12), θ3 = 2π - acos(c13): α = (θ2 + θ3 - 2π)/3
    alpha = (np.arccos(c12) - np.arccos(c13)) / 3.0
    # p1 tilted towards d about the unit axis p1 × d, to the angle acos(1/√3) from d
    v = work[1, 1]
    v[0] = p[0, 1] * d[2] - p[0, 2] * d[1]
    v[1] = p[0, 2] * d[0] - p[0, 0] * d[2]
    v[2] = p[0, 0] * d[1] - p[0, 1] * d[0]
    tilt = 0.5 * np.pi - _TRIPOD_ANGLE
    for i in range(3):
        v[i] *= tilt
    R = work[3]
    exp(v, R)
    start = work[1, 2]
    for i in range(3):
        start[i] = R[i, 0] * p[0, 0] + R[i, 1] * p[0, 1] + R[i, 2] * p[0, 2]
    for k in range(3):
        angle = alpha + k * (2.0 * np.pi / 3.0)
        for i in range(3):
            v[i] = angle * d[i]
        exp(v, R)
        for i in range(3):
            L[i, k] = R[i, 0] * start[0] + R[i, 1] * start[1] + R[i, 2] * start[2]


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
def point_psi(kind, F, L0, triads, lag, psi, work):
    """ψ = log(Λ_B Λ_Sᵀ) (3,) at one point.

    Parameters
    ----------
    kind : int
        POLAR, DEFORMATION_GRADIENT or SYMMETRIC.
    F : (3, 3)
        Deformation gradient of the solid at the point.
    L0 : (3, 3) float64
        Reference triad of the point.
    triads : (3, 3, 3)
        Current nodal triads of the beam element (line3 order).
    lag : (3,) float64
        Line3 Lagrange functions at the point.
    work : (8, 3, 3) scratch of the type of F.
    """
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
def _turn(k, v, triads, R, out):
    """``out`` = the triads with triad k turned by ``exp(v)`` (spatial spin)."""
    exp(v, R)
    for m in range(3):
        for i in range(3):
            for j in range(3):
                out[m, i, j] = triads[m, i, j]
    for i in range(3):
        for j in range(3):
            out[k, i, j] = R[i, 0] * triads[k, 0, j] + R[i, 1] * triads[k, 1, j] + R[i, 2] * triads[k, 2, j]


@njit
def _gradient(kind, F, L0, triads, lag, lam, out, cF, ct, R, psi, work):
    """``out[r] = λ_r · ∂ψ/∂p`` (rows r of ``lam``; 18 columns p: the 9 entries ``F[i, j]`` at
    ``3 i + j``, then the spins of the three triads) by the complex step."""
    status = OK
    v = np.zeros(3, dtype=np.complex128)
    for c in range(18):
        for i in range(3):
            for j in range(3):
                cF[i, j] = F[i, j]
        if c < 9:
            cF[c // 3, c % 3] += 1j * STEP
            for m in range(3):
                for i in range(3):
                    for j in range(3):
                        ct[m, i, j] = triads[m, i, j]
        else:
            v[:] = 0.0
            v[(c - 9) % 3] = 1j * STEP
            _turn((c - 9) // 3, v, triads, R, ct)
        status = max(status, point_psi(kind, cF, L0, ct, lag, psi, work))
        for r in range(lam.shape[0]):
            out[r, c] = (psi[0].imag * lam[r, 0] + psi[1].imag * lam[r, 1] + psi[2].imag * lam[r, 2]) / STEP
    return status


@njit
def point_jacobian(kind, F, L0, triads, lag, psi, J):
    """ψ (3,) and ``J = ∂ψ/∂(F, θ)`` (3, 18) at one point (real inputs); returns a status."""
    work = np.empty((8, 3, 3), dtype=np.complex128)
    cF = np.empty((3, 3), dtype=np.complex128)
    ct = np.empty((3, 3, 3), dtype=np.complex128)
    R = np.empty((3, 3), dtype=np.complex128)
    cpsi = np.empty(3, dtype=np.complex128)
    status = _gradient(kind, F, L0, triads, lag, np.eye(3), J, cF, ct, R, cpsi, work)
    return max(status, point_psi(kind, F, L0, triads, lag, psi, np.empty((8, 3, 3))))


@njit
def point_hessian(kind, F, L0, triads, lag, lam, H):
    """``H = ∂(Jᵀλ)/∂(F, θ)`` (18, 18) for a fixed λ (3,): central differences (step
    :data:`FD_STEP`, F being dimensionless and spins in radians) of the complex-step gradients.
    H must hold zeros on entry."""
    work = np.empty((8, 3, 3), dtype=np.complex128)
    cF = np.empty((3, 3), dtype=np.complex128)
    ct = np.empty((3, 3, 3), dtype=np.complex128)
    R = np.empty((3, 3), dtype=np.complex128)
    cpsi = np.empty(3, dtype=np.complex128)
    Fs = np.empty((3, 3))
    ts = np.empty((3, 3, 3))
    Rr = np.empty((3, 3))
    v = np.zeros(3)
    g = np.empty((1, 18))
    lam2 = lam.reshape(1, 3)
    status = OK
    for l in range(18):
        for sign in (1.0, -1.0):
            Fs[:, :] = F
            if l < 9:
                Fs[l // 3, l % 3] += sign * FD_STEP
                ts[:, :, :] = triads
            else:
                v[:] = 0.0
                v[(l - 9) % 3] = sign * FD_STEP
                _turn((l - 9) // 3, v, triads, Rr, ts)
            status = max(status, _gradient(kind, Fs, L0, ts, lag, lam2, g, cF, ct, R, cpsi, work))
            for c in range(18):
                H[c, l] += sign * g[0, c] / (2.0 * FD_STEP)
    return status


@njit
def _point_state(p, x, nodes, n_local, G, triads, rotation_nodes, beam_element, F, tl):
    """F (3, 3) from the current positions x and the element's nodal triads ``tl`` of point p."""
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for a in range(n_local[p]):
                acc += x[nodes[p, a], i] * G[p, a, j]
            F[i, j] = acc
    e = beam_element[p]
    for k in range(3):
        tl[k] = triads[rotation_nodes[e, k]]


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
    """ψ (n_pts, 3) at every point and, when ``want``, ``J = ∂ψ/∂(F, θ)`` (n_pts, 3, 18): columns
    ``3 i + j`` the entries F[i, j], then the spins of the point's beam element's rotation nodes
    (line3 order). x: current solid positions (n_solid_nodes, 3)."""
    F = np.empty((3, 3))
    tl = np.empty((3, 3, 3))
    work = np.empty((8, 3, 3))
    for p in range(len(beam_element)):
        _point_state(p, x, nodes, n_local, G, triads, rotation_nodes, beam_element, F, tl)
        if want:
            status[p] = point_jacobian(kind, F, L0[p], tl, lag[p], psi[p], J[p])
        else:
            status[p] = point_psi(kind, F, L0[p], tl, lag[p], psi[p], work)


@njit
def _hessian_points(begin, stop, kind, x, nodes, n_local, G, L0, triads, rotation_nodes, beam_element, lag, lam, H,
                    status):
    """:func:`hessian_range` of the points ``begin .. stop - 1``."""
    F = np.empty((3, 3))
    tl = np.empty((3, 3, 3))
    for p in range(begin, stop):
        status[p] = OK
        if lam[p, 0] == 0.0 and lam[p, 1] == 0.0 and lam[p, 2] == 0.0:
            continue
        _point_state(p, x, nodes, n_local, G, triads, rotation_nodes, beam_element, F, tl)
        status[p] = point_hessian(kind, F, L0[p], tl, lag[p], lam[p], H[p])


@njit
def hessian_range(kind, x, nodes, n_local, G, L0, triads, rotation_nodes, beam_element, lag, lam, H, status):
    """``H[p] = ∂(J_pᵀ λ_p)/∂(F, θ)`` (n_pts, 18, 18) in the layout of :func:`jacobian_range`;
    H must hold zeros on entry. Chunks of :data:`POINT_CHUNK` points run in parallel; every point
    is computed by the same serial code, so the result does not depend on the thread count."""
    n = len(beam_element)
    _hessian_range_workers((n + POINT_CHUNK - 1) // POINT_CHUNK, kind, x, nodes, n_local, G, L0, triads,
                          rotation_nodes, beam_element, lag, lam, H, status, n)


@njit
def _hessian_range_worker(c, kind, x, nodes, n_local, G, L0, triads, rotation_nodes, beam_element, lag, lam, H,
                         status, n):
    _hessian_points(c * POINT_CHUNK, min(n, (c + 1) * POINT_CHUNK), kind, x, nodes, n_local, G, L0, triads,
                    rotation_nodes, beam_element, lag, lam, H, status)


_hessian_range_workers = in_parallel(_hessian_range_worker)
