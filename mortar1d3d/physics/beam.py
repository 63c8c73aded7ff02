"""Hyperelastic beams on the centreline: torsion-free Kirchhoff beam (Hermite) and truss (line).

Both models are functions of the centreline only: the current curve is
``r(η) = Σ_k H_k(η; L) q_k`` with ``q = q0 + d`` (``q0 = beams.centreline_dofs()``) and the
reference element length L (docs/conventions.md §2). In the current configuration the Hermite nodal
tangents are free vectors, not unit vectors: this is the torsion-free ("reduced") Kirchhoff
model of Meier, Popp & Wall (CMAME 2015, 2016), which has no rotational DOFs and no torsion.

Per Gauss point, with the reference arc length s (``ds = J dη``, ``J = |r0'(η)|``):

=================  =========================================  ============================
quantity           formula                                    notes
=================  =========================================  ============================
axial strain       ``ε = |r_s| - 1 = |r'|/J - 1``              engineering strain
curvature          ``k = r_s × r_ss / |r_s|³``                 ``|k| = |r' × r''| / |r'|³``
energy density     ``W = ½ EA ε² + ½ EI |k|²``                 per reference length
=================  =========================================  ============================

``|k|`` is the geometric curvature of the current curve, independent of the parametrisation.
The torsion-free theory holds for initially straight centrelines only: :class:`BeamModel`
refuses a curved reference (see its Notes), so the reference curvature ``|k0|`` that the
element kernel still takes (energy ``½ EI (|k| - |k0|)²``) is zero for every element it
evaluates.

The element kernel returns, per element, the energy, the internal force vector
``f = ∂Π/∂q`` and the consistent tangent ``K = ∂²Π/∂q²`` (exact, symmetric). Elements are
evaluated in chunks (in parallel when there is more than one), each element into its own
slice by the same serial code; the global vector and the CSR matrix are summed afterwards
with :func:`numpy.bincount` in a fixed order, so results are bit-identical for any number
of threads.
"""
import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .._config import CHUNK, njit, njit_inline
from .._parallel import in_parallel
from ..elements.beam import evaluate
from ..quadrature import gauss_legendre
from ..mesh import BeamMesh
from .beam_types import beam_type

__all__ = ["Section", "section", "BeamModel", "end_moment", "line_force", "reference_curvature", "curved_elements",
           "N_GAUSS", "AXIAL_GAUSS"]

#: Gauss points per Hermite element (see :class:`BeamModel`)
N_GAUSS = 6
#: Gauss points of the axial term per Hermite element: reduced against membrane locking
AXIAL_GAUSS = 3
# reference curvature below this times 1/L is round-off of a straight element: treated as zero
_STRAIGHT = 1e-8
# current curvature below this times |k0| is the apex of the cone (|k| - |k0|)²
_APEX = 1e-8

# what the element kernel computes
_ENERGY, _FORCE, _TANGENT = 0, 1, 2


# -- section ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Section:
    """Section stiffnesses: axial ``EA`` (force) and bending ``EI`` (force × length²)."""

    EA: float
    EI: float


def _positive(value, name):
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return x


def section(E=None, radius=None, EA=None, EI=None):
    """Section stiffnesses from a circular cross section or given explicitly.

    Parameters
    ----------
    E, radius : float, optional
        Young's modulus and radius of a solid circular section: ``A = π r²``, ``I = π r⁴ / 4``.
    EA, EI : float, optional
        Explicit stiffnesses. Give either ``E`` and ``radius`` or ``EA`` and ``EI``.

    Returns
    -------
    Section

    Raises
    ------
    ValueError
        Both ways or neither given, a value missing, or a value zero, negative, NaN or infinite.
    """
    geometric = E is not None or radius is not None
    explicit = EA is not None or EI is not None
    if geometric and explicit:
        raise ValueError("section: give either E and radius, or EA and EI, not both")
    if geometric:
        if E is None or radius is None:
            raise ValueError("section: E and radius must be given together")
        E, r = _positive(E, "E"), _positive(radius, "radius")
        return Section(EA=E * math.pi * r * r, EI=E * math.pi * r ** 4 / 4.0)
    if explicit:
        if EA is None or EI is None:
            raise ValueError("section: EA and EI must be given together")
        return Section(EA=_positive(EA, "EA"), EI=_positive(EI, "EI"))
    raise ValueError("section: missing data; give E and radius, or EA and EI")


# -- kernels ---------------------------------------------------------------------------------------

@njit_inline
def cross_square_gradient(a, b, u, ab, bb, i):
    """(∂C/∂a_i, ∂C/∂b_i) of C = |a × b|² = u (b·b) − (a·b)² (Lagrange's identity), with
    ``u`` = a·a, ``ab`` = a·b, ``bb`` = b·b: the bending measures of both torsion-free beams."""
    return 2.0 * (bb * a[i] - ab * b[i]), 2.0 * (u * b[i] - ab * a[i])


@njit_inline
def cross_square_hessian(a, b, u, ab, bb, i, j):
    """(∂²C/∂a_i∂a_j, ∂²C/∂b_i∂b_j, ∂²C/∂a_i∂b_j, δ_ij) of C as in :func:`cross_square_gradient`."""
    delta = 1.0 if i == j else 0.0
    return (2.0 * (bb * delta - b[i] * b[j]), 2.0 * (u * delta - a[i] * a[j]),
            4.0 * a[i] * b[j] - 2.0 * b[i] * a[j] - 2.0 * ab * delta, delta)


@njit
def _gauss_point(a, b, a0, da, J, EA, EI, kappa0, want, grad, hess, work):
    """Energy density per reference length at one Gauss point, and its derivatives.

    Parameters
    ----------
    a, b : (3,) float64
        ``r'`` and ``r''`` (derivatives with respect to η) of the current centreline.
    a0, da : (3,) float64
        Reference ``r0'`` and its change ``a - a0`` (from the displacements alone): the axial
        strain is formed as ``(2 a0·da + da·da) / (J (|a| + J))`` so that it carries no
        cancellation error from the coordinates (``|a|/J - 1`` loses ``|X|/h`` digits, which a
        large EA turns into a residual floor far above round-off of the load).
    J : float
        Reference ``|r0'|``.
    EA, EI, kappa0 : float
        Stiffnesses and reference curvature ``|k0|`` (0: straight; ``EI = 0``: no bending).
    want : int
        0 energy, 1 and gradient, 2 and Hessian.
    grad : (6,) float64
        Output ``∂W/∂(a, b)``.
    hess : (6, 6) float64
        Output ``∂²W/∂(a, b)²``.
    work : (12,) float64
        Scratch (no allocation per Gauss point).

    Returns
    -------
    float
        W.

    Notes
    -----
    With ``u = a·a`` and Lagrange's identity ``C = |a × b|² = u (b·b) - (a·b)²`` the squared
    curvature ``p = |k|² = C / u³`` is a rational function of (a, b), smooth wherever
    ``a ≠ 0``; its first and second derivatives are written out below. For a curved reference
    ``|k| = √p`` and ``W_b = ½ EI (√p - κ0)²``, whose Hessian is
    ``EI [(1 - κ0/κ) p_xx / 2 + (κ0/κ) p_x p_xᵀ / (4p)]``. At the apex ``κ ≈ 0`` of that cone
    (a curved element bent exactly straight) the derivatives do not exist; there the
    straight-reference formulas are used (energy still exact).
    """
    u = a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
    na = math.sqrt(u)
    eps = (2.0 * (a0[0] * da[0] + a0[1] * da[1] + a0[2] * da[2]) + da[0] * da[0] + da[1] * da[1]
           + da[2] * da[2]) / (J * (na + J))
    W = 0.5 * EA * eps * eps
    if want >= 1:
        for i in range(6):
            grad[i] = 0.0
        g = EA * eps / (na * J)
        for i in range(3):
            grad[i] = g * a[i]
    if want >= 2:
        for i in range(6):
            for j in range(6):
                hess[i, j] = 0.0
        # EA (∂ε ∂εᵀ + ε ∂²ε), ∂ε = a/(|a| J), ∂²ε = (I - a aᵀ/u)/(|a| J)
        c1 = EA / (u * J * J) - EA * eps / (na * J * u)
        c0 = EA * eps / (na * J)
        for i in range(3):
            for j in range(3):
                hess[i, j] = c1 * a[i] * a[j]
            hess[i, i] += c0
    if EI == 0.0:
        return W

    ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2]
    C = max(u * bb - ab * ab, 0.0)     # round-off can make an exact zero slightly negative
    u3 = u * u * u
    u4 = u3 * u
    p = C / u3
    if kappa0 == 0.0:
        s1, s2, s_outer = 0.5 * EI, 0.5 * EI, 0.0
        W += 0.5 * EI * p
    else:
        kappa = math.sqrt(p)
        W += 0.5 * EI * (kappa - kappa0) * (kappa - kappa0)
        if kappa > _APEX * kappa0:
            ratio = kappa0 / kappa
            s1 = 0.5 * EI * (1.0 - ratio)       # factor of p_x in the gradient
            s2 = s1                             # factor of p_xx in the Hessian
            s_outer = EI * ratio / (4.0 * p)    # factor of p_x p_xᵀ
        else:
            s1, s2, s_outer = 0.0, 0.5 * EI, 0.0
    if want == 0:
        return W

    Ca = work[0:3]
    Cb = work[3:6]
    px = work[6:12]
    for i in range(3):
        Ca[i], Cb[i] = cross_square_gradient(a, b, u, ab, bb, i)
        px[i] = Ca[i] / u3 - 6.0 * C * a[i] / u4
        px[3 + i] = Cb[i] / u3
    for i in range(6):
        grad[i] += s1 * px[i]
    if want < 2:
        return W

    u5 = u4 * u
    for i in range(3):
        for j in range(3):
            Caa, Cbb, Cab, delta = cross_square_hessian(a, b, u, ab, bb, i, j)
            paa = (Caa / u3 - 6.0 * (Ca[i] * a[j] + a[i] * Ca[j]) / u4
                   + 48.0 * C * a[i] * a[j] / u5 - 6.0 * C * delta / u4)
            pab = Cab / u3 - 6.0 * a[i] * Cb[j] / u4
            pbb = Cbb / u3
            hess[i, j] += s2 * paa + s_outer * px[i] * px[j]
            hess[i, 3 + j] += s2 * pab + s_outer * px[i] * px[3 + j]
            hess[3 + j, i] += s2 * pab + s_outer * px[3 + j] * px[i]
            hess[3 + i, 3 + j] += s2 * pbb + s_outer * px[3 + i] * px[3 + j]
    return W


@njit
def _current_derivatives(dH, ddH, A0, B0, Qd, e, g, a, b, da):
    """Current ``r' = A0 + Σ dH_k Qd_k`` (into ``a``), its displacement part (``da``) and
    ``r'' = B0 + Σ ddH_k Qd_k`` (``b``) of element e at Gauss point g (arrays as in :func:`_element_range`)."""
    n_f = dH.shape[2]
    for i in range(3):
        da[i] = 0.0
        b[i] = 0.0
        for k in range(n_f):
            da[i] += dH[e, g, k] * Qd[e, k, i]
            b[i] += ddH[e, g, k] * Qd[e, k, i]
        a[i] = A0[e, g, i] + da[i]
        b[i] += B0[e, g, i]


@njit
def _element_range(first, last, dH, ddH, A0, B0, J, kappa0, EA_w, EI_w, Qd, want, energy, fe, ke):
    """Energy, internal force and tangent of elements ``first`` ... ``last - 1``.

    Parameters
    ----------
    dH, ddH : (n_el, n_g, n_f) float64
        ``dH_k/dη`` and ``d²H_k/dη²`` at the Gauss points (reference L).
    J, kappa0 : (n_el, n_g) float64
        Reference ``|r0'|`` and reference curvatures at the points.
    EA_w, EI_w : (n_el, n_g) float64
        Stiffnesses times the integration weight ``w J`` of the point; a point may serve
        only the axial (``EI_w = 0``) or only the bending term (``EA_w = 0``).
    A0, B0 : (n_el, n_g, 3) float64
        Reference ``r0'`` and ``r0''`` at the points (``J = |A0|``), formed from element-local
        coordinates (see :class:`BeamModel`).
    Qd : (n_el, n_f, 3) float64
        Displacement part ``q_k - q0_k`` of the current vector coefficients. The current
        ``r' = A0 + Σ dH_k Qd_k`` and ``r'' = B0 + Σ ddH_k Qd_k`` never touch absolute
        coordinates, so the result does not depend on where the model lies.
    want : int
        0 energy, 1 and forces, 2 and tangents.
    energy : (n_el,) float64
        Output.
    fe : (n_el, 3 n_f) float64
        Output (``want >= 1``), local DOF ``3k + i``.
    ke : (n_el, 3 n_f, 3 n_f) float64
        Output (``want == 2``), symmetric.
    """
    n_g, n_f = dH.shape[1], dH.shape[2]
    a = np.empty(3)
    b = np.empty(3)
    da = np.empty(3)
    grad = np.empty(6)
    hess = np.empty((6, 6))
    work = np.empty(12)
    for e in range(first, last):
        total = 0.0
        if want >= 1:
            fe[e, :] = 0.0
        if want == 2:
            ke[e, :, :] = 0.0
        for g in range(n_g):
            _current_derivatives(dH, ddH, A0, B0, Qd, e, g, a, b, da)
            total += _gauss_point(a, b, A0[e, g], da, J[e, g], EA_w[e, g], EI_w[e, g], kappa0[e, g], want, grad,
                                  hess, work)
            if want == 0:
                continue
            for k in range(n_f):
                for i in range(3):
                    fe[e, 3 * k + i] += (dH[e, g, k] * grad[i] + ddH[e, g, k] * grad[3 + i])
            if want < 2:
                continue
            for k in range(n_f):
                for l in range(k, n_f):
                    d1k, d2k, d1l, d2l = dH[e, g, k], ddH[e, g, k], dH[e, g, l], ddH[e, g, l]
                    for i in range(3):
                        for j in range(3):
                            ke[e, 3 * k + i, 3 * l + j] += (
                                d1k * d1l * hess[i, j] + d1k * d2l * hess[i, 3 + j]
                                + d2k * d1l * hess[3 + i, j] + d2k * d2l * hess[3 + i, 3 + j])
        energy[e] = total
        if want == 2:
            # mirror the upper triangle: exactly symmetric element (and so global) matrices
            for r in range(3 * n_f):
                for s in range(r + 1, 3 * n_f):
                    ke[e, s, r] = ke[e, r, s]


@njit
def _element_chunks(dH, ddH, A0, B0, J, kappa0, EA_w, EI_w, Qd, want, energy, fe, ke):
    """:func:`_element_range` over chunks of :data:`CHUNK` elements in parallel.

    Every element is computed by the same serial code whatever the thread count, so the
    outputs are bit-identical for any number of threads.
    """
    n_el = dH.shape[0]
    _element_chunks_workers((n_el + CHUNK - 1) // CHUNK, dH, ddH, A0, B0, J, kappa0, EA_w, EI_w, Qd, want, energy,
                            fe, ke, n_el)


@njit
def _element_chunks_worker(c, dH, ddH, A0, B0, J, kappa0, EA_w, EI_w, Qd, want, energy, fe, ke, n_el):
    _element_range(c * CHUNK, min(n_el, (c + 1) * CHUNK), dH, ddH, A0, B0, J, kappa0, EA_w, EI_w, Qd, want,
                   energy, fe, ke)


_element_chunks_workers = in_parallel(_element_chunks_worker)


# -- reference geometry (numpy) --------------------------------------------------------------------

def _tables(element, eta, lengths):
    """H, dH/dη, d²H/dη² of the centreline functions at ``eta`` per element: each (n_el, len(eta), n_f),
    from the element's own kernels (:func:`mortar1d3d.elements.beam.evaluate`)."""
    eta = np.asarray(eta, dtype=float)[None, :]
    lengths = np.asarray(lengths, dtype=float)[:, None]
    return tuple(np.ascontiguousarray(evaluate(element, eta, lengths, derivative=k)[..., : element.n_functions])
                 for k in range(3))


def _curve_derivatives(dH, ddH, Q):
    """r' and r'' (each (n_el, n_points, 3)) of coefficients Q (n_el, n_f, 3)."""
    return np.einsum("egk,eki->egi", dH, Q), np.einsum("egk,eki->egi", ddH, Q)


def _curvature(a, b):
    """|a × b| / |a|³ (geometric curvature) for stacks of r', r''."""
    return np.linalg.norm(np.cross(a, b), axis=-1) / np.linalg.norm(a, axis=-1) ** 3


#: parameters at which :func:`reference_curvature` samples each element: ``r0' × r0''`` of a cubic
#: is a cubic polynomial in η, so it vanishes on the element if it vanishes at four of them
_CURVATURE_SAMPLES = (-1.0, -0.5, 0.0, 0.5, 1.0)


def reference_curvature(beams):
    """Largest reference curvature times element length of every Hermite element.

    Parameters
    ----------
    beams : BeamMesh
        ``hermite`` centrelines (Lagrange ``line`` elements are straight: zeros).

    Returns
    -------
    (n_elements,) float64
        ``max_η |r0' × r0''| / |r0'|³ · L`` over η = -1, -1/2, 0, 1/2, 1: dimensionless, 0 for
        a straight element. A kink between two elements shows at the shared node, where the
        nodal tangent is not the chord direction (a polyline with averaged tangents).
    """
    if not beams.element_type.has_tangents:
        return np.zeros(beams.n_elements)
    _, dH, ddH = _tables(beams.element_type, _CURVATURE_SAMPLES, beams.lengths)
    Q = beams.coefficients()                  # r1, t1, r2, t2 per element
    # r0' and r0'' from the difference of the positions (dH1 = -dH3): no cancellation against |X|
    Q[:, 2] -= Q[:, 0]
    Q[:, 0] = 0.0
    a, b = _curve_derivatives(dH, ddH, Q)
    return _curvature(a, b).max(axis=1) * beams.lengths


def curved_elements(beams):
    """Ids and :func:`reference_curvature` of the curved elements of a Hermite beam mesh.

    An element is straight when its reference curvature times its length stays below 1e-8,
    or below the round-off of its stored node positions (``64 ε |X| / L``: a beam far from the
    origin cannot be straighter than its coordinates), whichever is larger.

    Returns
    -------
    ids : (k,) int64
    values : (k,) float64
    """
    value = reference_curvature(beams)
    if not beams.element_type.has_tangents:
        return np.zeros(0, np.int64), value[:0]
    X = np.abs(beams.positions[beams.elements[:, :2]]).max(axis=(1, 2))
    tolerance = np.maximum(_STRAIGHT, 64.0 * np.finfo(float).eps * X / beams.lengths)
    ids = np.flatnonzero(~(value <= tolerance))         # NaN (a cusp) counts as curved
    return ids, value[ids]


def curved_torsion_free_message(ids, values, n_elements):
    """Why a torsion-free beam refuses a curved reference centreline, and what to use instead."""
    from ..errors import format_ids
    worst = float(np.nanmax(values)) if np.isfinite(values).any() else float("nan")
    return (f"the torsion_free beam needs an initially straight centreline, but {len(ids)} of its {n_elements} "
            f"elements are curved (elements {format_ids(ids)}; reference curvature × element length up to "
            f"{worst:.3g}). Its bending energy ½EI(|k| − |k0|)² depends on the size of the curvature only, so a "
            "curved reference could change its bending plane at no cost (zero stiffness; the coupling does not "
            "hold it). Use model = \"simo_reissner\" (a geometrically exact beam with rotations) for curved "
            "beams, or model = \"truss\" for curved fibres without bending stiffness")


def _stiffness(value, name, n_elements, allow_zero=False):
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n_elements, float(arr))
    if arr.shape != (n_elements,):
        raise ValueError(f"{name}: expected a scalar or an array of shape ({n_elements},), got {arr.shape}")
    bad = ~np.isfinite(arr) | (arr < 0.0 if allow_zero else arr <= 0.0)
    if bad.any():
        what = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be {what} and finite; bad at elements {np.flatnonzero(bad)[:10].tolist()}")
    return np.ascontiguousarray(arr)


# -- model -----------------------------------------------------------------------------------------

class BeamModel:
    """Hyperelastic beams on a :class:`~mortar1d3d.mesh.BeamMesh`, exact consistent tangents.

    Parameters
    ----------
    beams : BeamMesh
        ``hermite`` centrelines for ``model="torsion_free"``, ``line`` for ``model="truss"``.
    EA : float or (n_elements,) array_like
        Axial stiffness, > 0.
    EI : float or (n_elements,) array_like or None
        Bending stiffness, > 0 for ``torsion_free``; ignored (may be None) for ``truss``.
    model : {"torsion_free", "truss"}
    n_gauss : int, optional
        Gauss points of the bending term per Hermite element (default 6).
    axial_gauss : int, optional
        Gauss points of the axial term per Hermite element (default 3, reduced; see Notes).
        The truss uses 1 point, which is exact.

    Attributes
    ----------
    n_dofs : int
        ``beams.n_centreline_dofs``; DOF layout of :meth:`BeamMesh.centreline_dofs`.
    n_evaluations : int
        Number of :meth:`evaluate` calls.

    Notes
    -----
    *Torsion-free Kirchhoff beam* (Meier, Popp & Wall, CMAME 2015/2016), per element
    ``Π_e = ∫ ½ EA ε² + ½ EI |k|² ds`` with ``ε = |r_s| - 1`` and
    ``k = r_s × r_ss / |r_s|³`` (module docstring): objective and smooth. The theory holds
    for initially straight beams with isotropic sections only, so a curved reference
    centreline (:func:`curved_elements`: reference curvature times element length above
    1e-8 anywhere, e.g. an arc, a helix, or a polyline with a kink) raises ValueError. The
    obvious extension ``½ EI (|k| - |k0|)²`` sees only the size of the curvature, not its
    direction: a change of the bending plane of a planar arc costs nothing, the tangent has
    no stiffness against it, and embedding the beam in a solid does not supply it (the
    ``line2`` coupling ties three of the six DOFs per node). Curved fibres need the truss, or
    a beam with a material frame (``simo_reissner``, :mod:`mortar1d3d.physics.simo_reissner`).

    *Gauss rules*: the bending term uses ``n_gauss`` points (default 6): on a straight
    reference element its linearised integrand ``(u'')²`` is a quadratic, and the nonlinear
    one is rational with numerator ``|r' × r''|²`` of degree 6 for the cubic centreline;
    6 points integrate degree 11 exactly, so the rule error stays far below the
    discretisation error (the tests compare with 10 points). The axial term uses its own
    ``axial_gauss`` points (default 3, *reduced*): sampling the quadratic axial strain of the
    cubic at 3 points is the smallest rule that still controls every axial mode (``u'`` is a
    quadratic: 3 values; 2 points leave a zero-energy mode), and it removes the membrane
    locking that the full rule shows for slender elements (the roll-up with
    ``EA L² / EI = 1e8`` and 4 elements: tip error 0.32 L with 6 axial points, 1.7e-3 L
    with 3). ``axial_gauss=n_gauss`` gives the fully integrated element. Both are exact
    derivatives of their discrete energy.

    *Boundary conditions*: at a Hermite node ``r' = (L/2) t``, so the length of a nodal
    tangent is the stretch ``1 + ε`` there. A clamp should fix the position and the tangent
    *direction* (e.g. ``t_y = t_z = 0`` for a beam along x), not ``|t|``: fixing all three
    tangent DOFs also forces ``ε = 0`` at that node, an O(h) boundary layer in the axial
    strain of an extensible beam (harmless when ``EA`` is large).

    *Truss*: 2-node ``line`` element, ``W = ½ EA ε²`` with the engineering strain
    ``ε = |r2 - r1| / L - 1`` (length change over reference length), tension and
    compression alike; no bending, no buckling resistance.
    """

    def __init__(self, beams, EA, EI=None, model="torsion_free", *, n_gauss=N_GAUSS, axial_gauss=AXIAL_GAUSS):
        if not isinstance(beams, BeamMesh):
            raise TypeError(f"BeamModel: expected a BeamMesh, got {type(beams).__name__}")
        kind = beam_type(model)         # NotImplementedError (planned) or ValueError (unknown)
        if kind.physics.split(":")[1] != "BeamModel":
            raise ValueError(f"beam model {model!r} is implemented by {kind.physics.replace(':', '.')}, not BeamModel")
        needed = kind.element.name
        if beams.element_type.name != needed:
            raise ValueError(f"beam model {model!r} needs a {needed!r} BeamMesh, got "
                             f"{beams.element_type.name!r} elements")
        self.beams = beams
        self.model = model
        self.type = kind
        n_el = beams.n_elements
        self.EA = _stiffness(EA, "EA", n_el)
        # this class implements the straight torsion-free beam (bending, Hermite) and the truss
        if kind.bending:
            if not kind.curved_reference:
                curved, curvature = curved_elements(beams)
                if curved.size:
                    raise ValueError(curved_torsion_free_message(curved, curvature, n_el))
            if EI is None:
                raise ValueError(f"the {model} model needs the bending stiffness EI")
            self.EI = _stiffness(EI, "EI", n_el)
            n_gauss = int(n_gauss)
            axial_gauss = n_gauss if axial_gauss is None else int(axial_gauss)
            if n_gauss < 2 or axial_gauss < 1:
                raise ValueError(f"need n_gauss >= 2 and axial_gauss >= 1 for Hermite elements, got "
                                 f"{n_gauss}, {axial_gauss}")
            eta, w = gauss_legendre(n_gauss)
            w_axial, w_bending = w, w
            if axial_gauss != n_gauss:
                # a separate (reduced) rule for the axial term: its points carry no bending
                eta_a, w_a = gauss_legendre(axial_gauss)
                eta = np.concatenate([eta, eta_a])
                w_axial = np.concatenate([np.zeros(n_gauss), w_a])
                w_bending = np.concatenate([w, np.zeros(axial_gauss)])
            _, dH, ddH = _tables(beams.element_type, eta, beams.lengths)
            n_f = 4
        else:
            if EI is not None and np.any(np.asarray(EI, dtype=float) != 0.0):
                warnings.warn(f"{model} model: EI is ignored (no bending)", stacklevel=2)
            self.EI = np.zeros(n_el)
            eta, w = gauss_legendre(1)
            w_axial, w_bending = w, 0.0 * w
            _, dH, ddH = _tables(beams.element_type, eta, beams.lengths)
            n_f = 2
        self.n_gauss = len(eta)
        self._dH = np.ascontiguousarray(dH)
        self._ddH = np.ascontiguousarray(ddH)
        self._q0 = beams.centreline_dofs()
        cols = beams.function_columns()[:, :n_f]
        self._dofs = np.ascontiguousarray((3 * cols[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_f))
        # position functions: their derivatives sum to zero, so r0' and r0'' follow from positions
        # relative to each element's first node; from absolute ones they would lose log10(|X|/L)
        # digits to cancellation (a model 1e5 m from the origin: r0'' = O(1e-11) instead of 0, a
        # spurious bending force that stalled Newton far above round-off of the load)
        self._position_function = np.array(beams.element_type.function_offset[:n_f]) == 0
        a0, b0 = _curve_derivatives(self._dH, self._ddH, self._local(self._coefficients(self._q0)))
        self._A0 = np.ascontiguousarray(a0)
        self._B0 = np.ascontiguousarray(b0)
        self._J = np.ascontiguousarray(np.linalg.norm(a0, axis=2))
        self._EA_w = np.ascontiguousarray(self.EA[:, None] * w_axial[None, :] * self._J)
        self._EI_w = np.ascontiguousarray(self.EI[:, None] * w_bending[None, :] * self._J)
        kappa0 = _curvature(a0, b0) if kind.bending else np.zeros_like(self._J)
        kappa0[kappa0 <= _STRAIGHT / beams.lengths[:, None]] = 0.0
        self._kappa0 = np.ascontiguousarray(kappa0)
        self._pattern = None
        self.n_evaluations = 0

    @property
    def n_dofs(self):
        return self.beams.n_centreline_dofs

    # -- internals ---------------------------------------------------------------------------------
    def _coefficients(self, q):
        n_el, nd = self._dofs.shape
        return np.ascontiguousarray(q[self._dofs].reshape(n_el, nd // 3, 3))

    def _local(self, Q):
        """Coefficients with every element's first node position subtracted from its position
        coefficients (tangents unchanged): the same r', r'', free of the coordinates' magnitude."""
        return Q - self._position_function[None, :, None] * Q[:, :1, :]

    def _displacement(self, d):
        d = np.asarray(d, dtype=float)
        if d.shape != (self.n_dofs,):
            raise ValueError(f"displacement: expected shape ({self.n_dofs},), got {d.shape}")
        if not np.isfinite(d).all():
            raise ValueError("displacement has NaN or infinite entries")
        return d

    def _current(self, d):
        return self._coefficients(self._q0 + self._displacement(d))

    def _run(self, d, want):
        Qd = self._coefficients(self._displacement(d))
        n_el, nd = self._dofs.shape
        energy = np.empty(n_el)
        fe = np.empty((n_el, nd) if want >= 1 else (0, 0))
        ke = np.empty((n_el, nd, nd) if want == 2 else (0, 0, 0))
        args = (self._dH, self._ddH, self._A0, self._B0, self._J, self._kappa0, self._EA_w, self._EI_w, Qd, want,
                energy, fe, ke)
        if n_el <= CHUNK:
            # one chunk: a parallel region would only add its launch cost (large on a busy machine)
            _element_range(0, n_el, *args)
        else:
            _element_chunks(*args)
        return energy, fe, ke

    def _csr_pattern(self):
        """CSR pattern of K and the map from element entries to CSR slots (built once)."""
        if self._pattern is None:
            n = self.n_dofs
            rows = np.repeat(self._dofs, self._dofs.shape[1], axis=1).ravel()
            cols = np.tile(self._dofs, (1, self._dofs.shape[1])).ravel()
            keys, slot = np.unique(rows * n + cols, return_inverse=True)
            indptr = np.zeros(n + 1, dtype=np.int64)
            np.cumsum(np.bincount(keys // n, minlength=n), out=indptr[1:])
            self._pattern = (indptr, (keys % n).astype(np.int64), slot.ravel(), len(keys))
        return self._pattern

    # -- public ------------------------------------------------------------------------------------
    def evaluate(self, d, tangent=True):
        """Internal force vector and (optionally) the consistent tangent at ``q = q0 + d``.

        Parameters
        ----------
        d : (n_dofs,) array_like of float
            Centreline displacement (positions and, for Hermite beams, tangent increments).
        tangent : bool

        Returns
        -------
        f_int : (n_dofs,) float64
            ``∂Π/∂d``.
        K : scipy.sparse.csr_matrix (n_dofs, n_dofs) or None
            ``∂²Π/∂d²`` (symmetric), None if ``tangent`` is False.
        """
        self.n_evaluations += 1
        _, fe, ke = self._run(d, _TANGENT if tangent else _FORCE)
        n = self.n_dofs
        # bincount sums in input order: the same bits for any thread count
        f = np.bincount(self._dofs.ravel(), weights=fe.ravel(), minlength=n)
        if not tangent:
            return f, None
        indptr, indices, slot, nnz = self._csr_pattern()
        data = np.bincount(slot, weights=ke.ravel(), minlength=nnz)
        K = sp.csr_matrix((data, indices, indptr), shape=(n, n))
        K.has_sorted_indices = True
        return f, K

    def energy(self, d):
        """Stored energy ``Π(q0 + d)`` (float)."""
        energy, _, _ = self._run(d, _ENERGY)
        return float(energy.sum())

    def sample(self, d, eta):
        """Current centreline quantities per element at parameters ``eta``.

        Parameters
        ----------
        d : (n_dofs,) array_like of float
        eta : (k,) array_like of float in [-1, 1]

        Returns
        -------
        dict of arrays
            ``"position"`` (n_el, k, 3), ``"displacement"`` (n_el, k, 3) (position minus the
            reference position), ``"axial_force"`` ``N = EA ε`` (n_el, k), ``"curvature"``
            ``|k|`` (n_el, k; zeros for trusses), ``"strain"`` ε (n_el, k).

        Notes
        -----
        For slender Hermite beams ``N = EA ε`` is a small difference of large numbers; it is
        most accurate at the axial Gauss points (``η = 0, ±√(3/5)`` for the default rule) and
        oscillates between them.
        """
        eta = np.atleast_1d(np.asarray(eta, dtype=float))
        if eta.ndim != 1 or not np.isfinite(eta).all():
            raise ValueError("eta: expected a 1D array of finite parameters")
        Q = self._current(d)
        Q0 = self._coefficients(self._q0)
        H, dH, ddH = _tables(self.beams.element_type, eta, self.beams.lengths)
        position = np.einsum("egk,eki->egi", H, Q)
        a, b = _curve_derivatives(dH, ddH, self._local(Q))
        a0, _ = _curve_derivatives(dH, ddH, self._local(Q0))
        # the kernels' cancellation-free axial strain (see _gauss_point), from the displacements
        da = np.einsum("egk,eki->egi", dH, self._coefficients(self._displacement(d)))
        J = np.linalg.norm(a0, axis=2)
        strain = (2.0 * np.einsum("egi,egi->eg", a0, da) + np.einsum("egi,egi->eg", da, da)) / (
            J * (np.linalg.norm(a, axis=2) + J))
        curvature = _curvature(a, b) if self.type.bending else np.zeros_like(strain)
        return {"position": position, "displacement": position - np.einsum("egk,eki->egi", H, Q0),
                "axial_force": self.EA[:, None] * strain, "curvature": curvature, "strain": strain}

    def __repr__(self):
        return f"BeamModel({self.model}, {self.beams.n_elements} elements, {self.n_dofs} DOFs)"


# -- loads -----------------------------------------------------------------------------------------

def end_moment(t, moment):
    """Load vector and its derivative of a moment applied through a Hermite node's tangent.

    Parameters
    ----------
    t : (3,) array_like of float
        Current nodal tangent vector (not necessarily unit).
    moment : (3,) array_like of float
        Moment vector M.

    Returns
    -------
    f : (3,) float64
        Generalised force on the node's tangent DOFs, ``f = M × t / |t|²``. It enters the
        residual as an external force: ``R = f_int - f_ext`` with ``f_ext ∋ f``.
    K : (3, 3) float64
        ``∂f/∂t = [M]ₓ / |t|² - 2 (M × t) tᵀ / |t|⁴`` (not symmetric); the Newton tangent
        gets ``-K`` on the tangent DOFs.

    Notes
    -----
    Virtual work ``δW = M · (t × δt) / |t|²`` = M times the rotation of the tangent direction
    about M. For planar bending about the moment axis (t ⟂ M, the tangent turns in the plane
    normal to M) this is the exact work of a conservative end moment, ``W = M θ`` with θ the
    angle of t in that plane, whatever the length of t; for general 3D motions it is only
    the component of the moment that a centreline without a material frame can take up.
    """
    t = np.asarray(t, dtype=float).reshape(3)
    M = np.asarray(moment, dtype=float).reshape(3)
    tt = float(t @ t)
    if not tt > 0.0:
        raise ValueError("end_moment: zero tangent vector")
    Mxt = np.cross(M, t)
    skew = np.array([[0.0, -M[2], M[1]], [M[2], 0.0, -M[0]], [-M[1], M[0], 0.0]])
    return Mxt / tt, skew / tt - 2.0 * np.outer(Mxt, t) / (tt * tt)


#: Gauss points per element of :func:`line_force` (exact for a straight element: a cubic integrand)
LINE_LOAD_GAUSS = 6


def line_force(beams, elements, value):
    """Consistent nodal forces of a dead line load (force per reference length) on beam elements.

    Parameters
    ----------
    beams : BeamMesh
    elements : (m,) int array_like
        The loaded elements.
    value : (3,) array_like of float
        Force per unit reference arc length.

    Returns
    -------
    dofs : (m · 3 n_f,) int64
        Centreline DOFs of ``beams`` (its :meth:`~mortar1d3d.mesh.BeamMesh.centreline_dofs` layout).
    f : (m · 3 n_f,) float64
        ``∫ H_k q ds`` per element function k and component, with ``ds = |r0'| dη`` and
        :data:`LINE_LOAD_GAUSS` Gauss points (for Hermite elements the tangent functions get their
        share too).
    """
    elements = np.asarray(elements, dtype=np.int64)
    q = np.asarray(value, dtype=float).reshape(3)
    n_f = beams.element_type.n_functions
    eta, w = gauss_legendre(LINE_LOAD_GAUSS)
    H, J = reference_speed(beams, elements, eta)
    weights = np.einsum("egk,eg->ek", H[..., :n_f], J * w[None, :])
    cols = beams.function_columns()[elements, :n_f]
    dofs = (3 * cols[:, :, None] + np.arange(3)).ravel()
    return dofs, (weights[:, :, None] * q[None, None, :]).ravel()


def reference_speed(beams, elements, eta):
    """The centreline functions ``H`` (m, n_g, n) and the reference speed ``|r0'(η)|`` (m, n_g)
    of beam ``elements`` at the parameters ``eta`` (n_g,)."""
    kind = beams.element_type
    n_f = kind.n_functions
    H, dH, _ = _tables(kind, eta, beams.lengths[elements])
    Q0 = beams.coefficients(elements)[:, :n_f]
    position = np.array(kind.function_offset[:n_f]) == 0
    # r0' from positions relative to each element's first node (no cancellation against |X|)
    Q0 = Q0 - position[None, :, None] * Q0[:, :1, :]
    return H, np.linalg.norm(np.einsum("egk,eki->egi", dH[..., :n_f], Q0), axis=2)
