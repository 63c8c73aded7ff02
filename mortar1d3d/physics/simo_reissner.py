"""Geometrically exact Simo–Reissner beam on a Hermite centreline with three-node triads (``herm2line3``).

The element (:mod:`.simo_reissner_kernel`) follows Simo (CMAME 49, 1985) and Simo & Vu-Quoc
(CMAME 58, 1986) for the strains and the section law, Crisfield & Jelenić (Proc R Soc A 455, 1999)
for the objective, path-independent triad interpolation, and the Hermite centreline of Meier,
Popp & Wall (Arch Comput Methods Eng 26, 2019) as used for beam-to-solid coupling.

Unknowns of a :class:`SimoReissnerBeam`:

- the centreline DOFs of :meth:`mortar1d3d.mesh.BeamMesh.centreline_dofs` (``[r, t]`` per mesh
  node, additive: ``q = q0 + d``);
- one triad per *rotation node*: first the mesh's nodes (shared element ends, same ids), then one
  middle node per element (id ``n_nodes + e``). The state is a total spatial rotation vector ψ per
  rotation node, ``Λ = exp(ψ) Λ0`` with the reference triad Λ0 (:func:`reference_triads`); Newton
  updates it multiplicatively, ``Λ ← exp(Δθ) Λ`` (:meth:`SimoReissnerBeam.update`).

The force vector and the tangent are in the layout ``[centreline DOFs | 3 per rotation node]``;
the rotation entries are conjugate to the spatial spin increments Δθ (moments).
"""
import math
from dataclasses import dataclass, fields

import numpy as np
import scipy.sparse as sp

from .._config import CHUNK
from ..elements.beam import BEAM_ELEMENTS, evaluate
from ..errors import RotationRangeError, format_ids
from ..mesh import BeamMesh
from ..quadrature import gauss_legendre
from . import simo_reissner_kernel as kernel
from .beam import BeamModel, _positive
from .rotations import compose_rows, exp_rows

__all__ = ["Section", "SimoReissnerBeam", "line_moment", "reference_triads", "check_triads", "RotationRangeError",
           "N_GAUSS", "FORCE_GAUSS", "FORCE_RULES", "LOBATTO3", "VIRTUAL_SPINS"]

#: Gauss points of the moment (curvature) term per element (see :class:`SimoReissnerBeam` Notes)
N_GAUSS = 3
#: Gauss points of the force (Γ) term per element (None: the same rule as the moment term, so that
#: both share their points); an int or one per component Γ1, Γ2, Γ3
FORCE_GAUSS = None
#: rules of the force term a beam may choose (``force_rule``): ``"gauss"`` (Gauss–Legendre with
#: ``force_gauss`` points) or ``"lobatto3"`` (3-point Gauss–Lobatto, :data:`LOBATTO3`)
FORCE_RULES = ("gauss", "lobatto3")
#: virtual spins of the residual's spin rows a beam may choose (``virtual_spins``): ``"exact"`` (the
#: variation of the interpolated triads, the residual is the energy's gradient) or ``"lagrange"``
#: (spins interpolated with the line3 Lagrange functions, 4C's ``BEAM3R``)
VIRTUAL_SPINS = ("exact", "lagrange")
#: the 3-point Gauss–Lobatto rule on [-1, 1]: points (-1, 0, 1), weights (1/3, 4/3, 1/3)
LOBATTO3 = (np.array([-1.0, 0.0, 1.0]), np.array([1.0, 4.0, 1.0]) / 3.0)
#: given reference triads: largest |ΛᵀΛ - I| accepted (then projected to the nearest rotation)
ORTHONORMAL_TOL = 1e-8
#: given reference triads: largest |g1 - t| against the unit reference tangent t
TANGENT_TOL = 1e-6


# -- section ---------------------------------------------------------------------------------------

def _shear_modulus(E, G, nu, where):
    if (G is None) == (nu is None):
        raise ValueError(f"{where}: give exactly one of G and nu")
    if G is not None:
        return _positive(G, f"{where}.G")
    try:
        nu = float(nu)
    except (TypeError, ValueError):
        raise ValueError(f"{where}.nu must be a number, got {nu!r}") from None
    if not (-1.0 < nu <= 0.5):
        raise ValueError(f"{where}.nu must lie in (-1, 0.5], got {nu!r}")
    return E / (2.0 * (1.0 + nu))


@dataclass(frozen=True)
class Section:
    """Section stiffnesses of a Simo–Reissner beam (principal axes g2, g3 of the section).

    Attributes
    ----------
    EA : float
        Axial stiffness (force).
    GA2, GA3 : float
        Shear stiffnesses along g2, g3 (force): G times the shear areas (shear correction × A).
    GI_T : float
        Torsional stiffness (force × length²).
    EI2, EI3 : float
        Bending stiffnesses about g2, g3 (force × length²).

    Build one from material and geometry with :meth:`from_properties` or :meth:`circular`, or give
    the six stiffnesses. Every value must be positive and finite (ValueError naming it).
    """

    EA: float
    GA2: float
    GA3: float
    GI_T: float
    EI2: float
    EI3: float

    def __post_init__(self):
        for f in fields(self):
            object.__setattr__(self, f.name, _positive(getattr(self, f.name), f"section.{f.name}"))

    @classmethod
    def from_properties(cls, E, A, I2, I3, I_T, shear_correction, G=None, nu=None):
        """Stiffnesses from Young's modulus E, G (or Poisson's ratio nu), the area A, the second
        moments I2, I3 (about g2, g3), the torsion constant I_T and the shear correction factor
        (one number, or a pair for g2 and g3): ``GA_i = G k_i A``."""
        E = _positive(E, "section.E")
        G = _shear_modulus(E, G, nu, "section")
        A = _positive(A, "section.A")
        k = np.broadcast_to(np.asarray(shear_correction, dtype=object), (2,))
        k2, k3 = _positive(k[0], "section.shear_correction"), _positive(k[1], "section.shear_correction")
        return cls(EA=E * A, GA2=G * k2 * A, GA3=G * k3 * A, GI_T=G * _positive(I_T, "section.I_T"),
                   EI2=E * _positive(I2, "section.I2"), EI3=E * _positive(I3, "section.I3"))

    @classmethod
    def circular(cls, E, radius, G=None, nu=None, shear_correction=None):
        """Solid circular section of ``radius``: ``A = π r²``, ``I2 = I3 = π r⁴/4``, ``I_T = π r⁴/2``.
        The shear correction defaults to Cowper's ``6(1 + ν)/(7 + 6ν)`` (J Appl Mech 33, 1966),
        with ν from G if G is given."""
        E = _positive(E, "section.E")
        G = _shear_modulus(E, G, nu, "section")
        r = _positive(radius, "section.radius")
        if shear_correction is None:
            shear_correction = cowper_shear_correction(E / (2.0 * G) - 1.0)
        A, I = math.pi * r * r, math.pi * r ** 4 / 4.0
        return cls.from_properties(E, A, I, I, 2.0 * I, shear_correction, G=G)

    @property
    def force_stiffness(self):
        """``(EA, GA2, GA3)`` (3,) float64: the diagonal of C_F."""
        return np.array([self.EA, self.GA2, self.GA3])

    @property
    def moment_stiffness(self):
        """``(GI_T, EI2, EI3)`` (3,) float64: the diagonal of C_M."""
        return np.array([self.GI_T, self.EI2, self.EI3])


def cowper_shear_correction(nu):
    """Shear correction factor of a solid circular section, ``6(1 + ν) / (7 + 6ν)`` (Cowper, J Appl
    Mech 33, 1966)."""
    return 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)


# -- reference triads ------------------------------------------------------------------------------

def _rotation_node_tangents(beams):
    """Unit reference tangents at the rotation nodes (n_nodes + n_elements, 3)."""
    Q = beams.coefficients()[:, :4]
    dH = evaluate(beams.element_type, 0.0, beams.lengths, derivative=1)[:, :4]
    mid = np.einsum("ek,eki->ei", dH, Q - np.array([1.0, 0.0, 1.0, 0.0])[None, :, None] * Q[:, :1])
    mid /= np.linalg.norm(mid, axis=1)[:, None]
    return np.vstack([beams.tangents, mid])


def _transport(t_a, t_b, v):
    """v turned by the smallest rotation taking unit t_a to unit t_b (None if t_b ≈ -t_a)."""
    c = float(t_a @ t_b)
    if c <= -1.0 + 1e-12:
        return None
    k = np.cross(t_a, t_b)
    return v * c + np.cross(k, v) + k * (k @ v) / (1.0 + c)


def _rotation_node_table(beams):
    n = beams.n_nodes
    return np.column_stack([beams.elements[:, 0], beams.elements[:, 1], n + np.arange(beams.n_elements)])


def reference_triads(beams, normal=None):
    """Reference triads at the rotation nodes by parallel transport along each beam.

    Parameters
    ----------
    beams : BeamMesh
        ``hermite`` centrelines.
    normal : (3,) array_like, optional
        Direction of g2 at the first node of each beam, projected normal to its tangent; default
        the coordinate axis least aligned with that tangent.

    Returns
    -------
    (n_nodes + n_elements, 3, 3) float64
        Columns g1 (unit reference tangent; at a middle node ``r0'(0)/|r0'(0)|``), g2, g3 = g1 × g2
        per rotation node (mesh nodes, then one middle node per element).

    Notes
    -----
    Along each connected beam, elements are visited from its lowest-numbered element, and g2 is
    carried node → middle → node by the rotation-minimising map (the smallest rotation taking one
    tangent to the next), so the frame does not twist about the centreline more than the curve
    makes it. A node reached a second time (a closed loop) keeps its first frame.
    """
    if not isinstance(beams, BeamMesh) or beams.element_type.name != "hermite":
        raise ValueError("reference_triads: expected a hermite BeamMesh")
    t = _rotation_node_tangents(beams)
    nodes = _rotation_node_table(beams)
    n_rot = len(t)
    g2 = np.full((n_rot, 3), np.nan)
    if normal is not None:
        normal = np.asarray(normal, dtype=float).reshape(3)
        if not np.isfinite(normal).all() or not np.linalg.norm(normal) > 0:
            raise ValueError(f"reference_triads: normal must be a finite nonzero vector, got {normal}")
    by_node = [[] for _ in range(beams.n_nodes)]
    for e, (a, b) in enumerate(beams.elements[:, :2]):
        by_node[a].append(e)
        by_node[b].append(e)
    done = np.zeros(beams.n_elements, dtype=bool)
    for start in range(beams.n_elements):
        if done[start]:
            continue
        stack = [start]
        while stack:
            e = stack.pop()
            if done[e]:
                continue
            done[e] = True
            a, b, m = nodes[e]
            path = (b, m, a) if np.isnan(g2[a, 0]) and not np.isnan(g2[b, 0]) else (a, m, b)
            if np.isnan(g2[path[0], 0]):
                t0 = t[path[0]]
                v = np.eye(3)[np.argmin(np.abs(t0))] if normal is None else normal
                v = v - (v @ t0) * t0
                if not np.linalg.norm(v) > 1e-8 * np.linalg.norm(normal if normal is not None else t0):
                    raise ValueError(f"reference_triads: normal {normal} is parallel to the tangent at node "
                                     f"{path[0]}")
                g2[path[0]] = v / np.linalg.norm(v)
            for p, q in zip(path[:-1], path[1:]):
                if not np.isnan(g2[q, 0]):
                    continue
                v = _transport(t[p], t[q], g2[p])
                if v is None:
                    raise ValueError(f"reference_triads: the tangent reverses between rotation nodes {p} and {q} "
                                     f"(element {e}): no parallel transport")
                v = v - (v @ t[q]) * t[q]
                g2[q] = v / np.linalg.norm(v)
            for node in (a, b):
                stack.extend(x for x in by_node[node] if not done[x])
    return np.ascontiguousarray(np.stack([t, g2, np.cross(t, g2)], axis=2))


def check_triads(beams, triads, orthonormal_tol=ORTHONORMAL_TOL, tangent_tol=TANGENT_TOL):
    """Validated reference triads (n_nodes + n_elements, 3, 3): orthonormal within
    ``orthonormal_tol`` (then projected to the nearest rotation), right-handed, and g1 (column 0)
    within ``tangent_tol`` of the unit reference tangent. ValueError naming the rotation nodes
    otherwise."""
    n_rot = beams.n_nodes + beams.n_elements
    L = np.asarray(triads, dtype=float)
    if L.shape != (n_rot, 3, 3):
        raise ValueError(f"reference triads: expected shape ({n_rot}, 3, 3) (mesh nodes, then one middle node "
                         f"per element), got {L.shape}")
    bad = np.flatnonzero(~np.isfinite(L).all(axis=(1, 2)))
    if bad.size:
        raise ValueError(f"reference triads: NaN or infinite entries at rotation nodes {format_ids(bad)}")
    error = np.abs(np.einsum("kji,kjl->kil", L, L) - np.eye(3)).max(axis=(1, 2))
    bad = np.flatnonzero(error > orthonormal_tol)
    if bad.size:
        raise ValueError(f"reference triads are not orthonormal at rotation nodes {format_ids(bad)} "
                         f"(|ΛᵀΛ - I| up to {error[bad].max():.3g} > {orthonormal_tol:g})")
    bad = np.flatnonzero(np.linalg.det(L) < 0.0)
    if bad.size:
        raise ValueError(f"reference triads are left-handed at rotation nodes {format_ids(bad)} (g3 must be g1 × g2)")
    U, _, Vt = np.linalg.svd(L)
    L = U @ Vt                              # nearest rotation: exactly orthonormal to round-off
    t = _rotation_node_tangents(beams)
    off = np.linalg.norm(L[:, :, 0] - t, axis=1)
    bad = np.flatnonzero(off > tangent_tol)
    if bad.size:
        raise ValueError(f"reference triads: g1 is not the unit reference tangent at rotation nodes {format_ids(bad)} "
                         f"(|g1 - t| up to {off[bad].max():.3g} > {tangent_tol:g}; rotation nodes are the mesh "
                         f"nodes, then one middle node per element)")
    return np.ascontiguousarray(L)


# -- model -----------------------------------------------------------------------------------------

def _lagrange_tables(eta):
    line3 = BEAM_ELEMENTS["line3"]
    eta = np.asarray(eta, dtype=float)
    return tuple(np.ascontiguousarray(evaluate(line3, eta, derivative=k)[:, :3]) for k in range(2))


def line_moment(beam, elements, value):
    """Nodal moments of a dead moment per reference length on Simo–Reissner beam elements.

    The virtual work ``∫ m · δθ ds`` with the spins interpolated by the line3 Lagrange functions
    L_k of the element's three rotation nodes: ``M_k = ∫ L_k m ds`` (``ds = |r0'| dη``,
    :data:`~mortar1d3d.physics.beam.LINE_LOAD_GAUSS` Gauss points), fixed in space and
    independent of the deformation, so no tangent. The exact spin interpolation of the element
    (``Ĩ_k``, :mod:`.simo_reissner_kernel`) equals ``L_k I`` where the triads turn about one fixed
    axis (a planar problem) and differs from it at the order of the rotations' out-of-plane part
    otherwise; 4C's BEAM3R distributes a line moment with the same ``L_k`` (and no tangent).

    Parameters
    ----------
    beam : SimoReissnerBeam
    elements : (m,) int array_like
    value : (3,) array_like of float
        Moment per unit reference arc length, spatial components.

    Returns
    -------
    nodes : (3 m,) int64
        Rotation nodes (:attr:`SimoReissnerBeam.rotation_nodes`), three per element.
    moments : (3 m, 3) float64
    """
    from .beam import LINE_LOAD_GAUSS, reference_speed
    elements = np.asarray(elements, dtype=np.int64)
    eta, w = gauss_legendre(LINE_LOAD_GAUSS)
    J = reference_speed(beam.beams, elements, eta)[1]
    weights = np.einsum("gk,eg->ek", _lagrange_tables(eta)[0], J * w[None, :])
    return beam.rotation_nodes[elements].ravel(), weights.ravel()[:, None] * np.asarray(value, dtype=float)[None, :]


class SimoReissnerBeam:
    """Simo–Reissner beams (``herm2line3``) on a Hermite :class:`~mortar1d3d.mesh.BeamMesh`.

    Parameters
    ----------
    beams : BeamMesh
        ``hermite`` centrelines; straight or curved.
    section : Section or sequence of Section
        One section for all elements, or one per element.
    reference_triads : (n_rotation_nodes, 3, 3) array_like, optional
        Given reference triads (checked by :func:`check_triads`); default :func:`reference_triads`.
    n_gauss : int, optional
        Gauss points of the moment term per element (default 3).
    force_gauss : int or 3 ints, optional
        Gauss points of the force term per element, or per component (Γ1, Γ2, Γ3); default
        ``n_gauss`` (see Notes before reducing it).
    force_rule : str or sequence of str, optional
        Rule of the force term, one for all elements or one per element (:data:`FORCE_RULES`):
        ``"gauss"`` (default: Gauss–Legendre with ``force_gauss`` points) or ``"lobatto3"`` (3-point
        Gauss–Lobatto, η = -1, 0, 1 with weights 1/3, 4/3, 1/3, for all three components; the
        moment term keeps its ``n_gauss`` Gauss points). See Notes.
    virtual_spins : str or sequence of str, optional
        Test functions of the spin rows, one for all elements or one per element
        (:data:`VIRTUAL_SPINS`): ``"exact"`` (default) or ``"lagrange"``. See Notes.

    Attributes
    ----------
    n_centreline_dofs, n_rotation_nodes, n_dofs : int
        ``n_dofs = n_centreline_dofs + 3 n_rotation_nodes``.
    rotation_nodes : (n_elements, 3) int64
        Rotation nodes of each element in line3 order (start, end, middle).
    triads0 : (n_rotation_nodes, 3, 3) float64
        Reference triads (columns g1, g2, g3).
    CF, CM : (n_elements, 3) float64
        Section stiffness diagonals per element.
    n_evaluations : int
        Number of :meth:`evaluate` calls.

    Notes
    -----
    The tangent is exact to round-off: its rotation columns are the complex-step derivative of the
    residual (9 residual evaluations in complex arithmetic per element), its centreline columns are
    written out (:mod:`.simo_reissner_kernel`). One evaluation with the tangent costs about 30 times
    the torsion-free beam's, the force alone about 1.7 times (``benchmarks/simo_reissner.py``).

    *Gauss rules.* The default is 3 points for both terms (shared points). It is the smallest
    rule without spurious zero-energy modes: with 2 points for the force term the strain Γ of a
    cubic centreline is sampled where its quadratic part ``η² - 1/3`` vanishes, and every beam
    gets 3 zero-energy modes (a wiggle of the centreline inside every element with the same
    change of all nodal tangents; measured: 9 zero eigenvalues of a free beam instead of the 6
    rigid motions, for any number of elements). The full rule locks for slender coarse meshes
    (axial and shear constraints on a curved or bent element): a quarter arc R = 1 with a
    circular section r = 1e-3 under an in-plane tip load has a tip error of 0.31 with 4
    elements, 1.6e-2 with 8, 7.6e-4 with 16 (1.3e-4 with the 2-point force rule); the end-moment
    roll-up of a straight cantilever (L/r = 1000) into a full circle misses the root by 0.53 L
    with 4 elements, 0.20 L with 8, 7.9e-3 L with 16. ``force_gauss=2`` removes this locking (the
    roll-up is then exact to round-off with any number of elements) and is safe when the zero-
    energy modes are held otherwise: a centreline coupled to a solid along its length, or a node
    whose tangent is fixed (a clamp of position, tangent and triad; note that fixing the tangent
    also fixes the shear at that node, an O(h) error of the deflection inside the elements when
    the root carries a shear force). Moment rules of 2 to 5 points give the same results to the
    discretisation error (``benchmarks/simo_reissner.py`` measures all of these).

    ``force_rule="lobatto3"`` is the rule of 4C's ``BEAM3R`` element with a Hermite centreline
    (its "reduced integration of elastic residual contributions from forces"; the moment term
    there is the 3-point Gauss rule too): the force term is sampled at the element's ends and
    middle. It samples the quadratic part ``η² - 1/3`` of Γ at nonzero values, so it has none of
    the 2-point rule's spurious modes. The 4C reader chooses it for every ``BEAM3R`` element. The
    reference strains Γ0, K0 are always taken at the same points as the terms that use them, so
    that a curved reference stays stress-free with either rule.

    *Virtual spins.* With ``"exact"`` the spin rows are the internal virtual work in the exact
    variation of the interpolated triad field, ``δθ(η) = Σ_k Ĩ_k(η) δθ_k`` (Ĩ_k the generalised
    interpolation matrices of Jelenić & Crisfield 1999), so the residual is the gradient of the
    stored energy. ``"lagrange"`` interpolates the virtual spins with the line3 Lagrange
    functions instead, ``δθ(η) = Σ_k L_k(η) δθ_k``: the spin rows are
    ``Σ_g w_g J_g [L_k (n × r_s) + L_k,s m]`` (n, m the spatial force and moment), the internal
    force vector of Jelenić & Crisfield 1999, eq. (4.3), and of 4C's ``BEAM3R`` element
    (``Beam3r::calc_internal_force_and_stiff``); it is a Petrov–Galerkin form, not
    the gradient of an energy. The two agree while an element's triads turn about one common
    axis (Ĩ_k = L_k I, every plane problem); otherwise they differ at the order of the relative
    nodal rotations times the section moments, and converge to the same solution as the mesh is
    refined. The 4C reader chooses ``"lagrange"`` for every ``BEAM3R`` element.
    """

    def __init__(self, beams, section, reference_triads=None, *, n_gauss=N_GAUSS, force_gauss=FORCE_GAUSS,
                 force_rule="gauss", virtual_spins="exact"):
        if not isinstance(beams, BeamMesh):
            raise TypeError(f"SimoReissnerBeam: expected a BeamMesh, got {type(beams).__name__}")
        if beams.element_type.name != "hermite":
            raise ValueError(f"SimoReissnerBeam needs a 'hermite' BeamMesh, got {beams.element_type.name!r} elements")
        self.beams = beams
        n_el = beams.n_elements
        sections = [section] * n_el if isinstance(section, Section) else list(section)
        if len(sections) != n_el or not all(isinstance(s, Section) for s in sections):
            raise ValueError(f"section: expected a Section or {n_el} Sections (one per element)")
        self.sections = sections
        self.CF = np.ascontiguousarray([s.force_stiffness for s in sections])
        self.CM = np.ascontiguousarray([s.moment_stiffness for s in sections])
        self.rotation_nodes = np.ascontiguousarray(_rotation_node_table(beams), dtype=np.int64)
        self.n_rotation_nodes = beams.n_nodes + n_el
        self.n_centreline_dofs = beams.n_centreline_dofs
        self.n_dofs = self.n_centreline_dofs + 3 * self.n_rotation_nodes
        if reference_triads is None:
            self.triads0 = _default_triads(beams)
        else:
            self.triads0 = check_triads(beams, reference_triads)
        n_gauss = int(n_gauss)
        force_gauss = n_gauss if force_gauss is None else force_gauss
        force_gauss = tuple(int(x) for x in np.broadcast_to(np.asarray(force_gauss), (3,)))
        if n_gauss < 1 or min(force_gauss) < 1:
            raise ValueError(f"need n_gauss >= 1 and force_gauss >= 1, got {n_gauss}, {force_gauss}")
        self.n_gauss, self.force_gauss = n_gauss, force_gauss
        self.force_rule = _per_element(force_rule, n_el, FORCE_RULES, "force_rule")
        self.virtual_spins = _per_element(virtual_spins, n_el, VIRTUAL_SPINS, "virtual_spins")
        self._spins = np.ascontiguousarray(np.where(self.virtual_spins == "lagrange", kernel.LAGRANGE, kernel.EXACT),
                                           dtype=np.int64)
        lobatto = self.force_rule == "lobatto3"
        eta, wF, wM, wL = _rules(n_gauss, force_gauss, lobatto.any())
        self._q0 = beams.centreline_dofs()
        cols = beams.function_columns()[:, :4]
        cl = (3 * cols[:, :, None] + np.arange(3)).reshape(n_el, 12)
        rot = (self.n_centreline_dofs + 3 * self.rotation_nodes[:, :, None] + np.arange(3)).reshape(n_el, 9)
        self._dofs = np.ascontiguousarray(np.hstack([cl, rot]))
        self._points = self._tables(eta)
        dH, lag, dlag, A0, J = self._points
        if wL is None:
            self._wF = np.ascontiguousarray(wF[None, :, :] * J[:, :, None])
        else:
            self._wF = np.ascontiguousarray(np.where(lobatto[:, None, None], wL[None], wF[None]) * J[:, :, None])
        self._wM = np.ascontiguousarray(wM[None, :] * J)
        reference = self._element_triads(self.triads0)
        self._Gamma0, self._K0, _ = self._strains(self._points, np.zeros((n_el, 4, 3)), reference)
        self._pattern = None
        self.n_evaluations = 0

    # -- internals ---------------------------------------------------------------------------------
    def _tables(self, eta):
        """dH (n_el, n_p, 4), Lagrange values and derivatives (n_p, 3), r0' (n_el, n_p, 3), J (n_el, n_p)."""
        eta = np.asarray(eta, dtype=float)
        dH = np.ascontiguousarray(evaluate(self.beams.element_type, eta[None, :], self.beams.lengths[:, None],
                                           derivative=1)[..., :4])
        lag, dlag = _lagrange_tables(eta)
        Q0 = self._coefficients(self._q0)
        Q0 = Q0 - np.array([1.0, 0.0, 1.0, 0.0])[None, :, None] * Q0[:, :1]     # relative to the first node
        A0 = np.ascontiguousarray(np.einsum("egk,eki->egi", dH, Q0))
        return dH, lag, dlag, A0, np.ascontiguousarray(np.linalg.norm(A0, axis=2))

    def _coefficients(self, q):
        return np.ascontiguousarray(q[self._dofs[:, :12]].reshape(-1, 4, 3))

    def _element_triads(self, triads):
        return np.ascontiguousarray(triads[self.rotation_nodes])

    def _strains(self, points, Dd, triads_e):
        dH, lag, dlag, A0, J = points
        n_el, n_p = J.shape
        Gamma, Kappa = np.empty((n_el, n_p, 3)), np.empty((n_el, n_p, 3))
        Lam = np.empty((n_el, n_p, 3, 3))
        status = np.empty(n_el, dtype=np.int64)
        kernel.strain_range(dH, lag, dlag, A0, J, Dd, triads_e, Gamma, Kappa, Lam, status)
        self._check_status(status)
        return Gamma, Kappa, Lam

    def _check_status(self, status):
        bad = np.flatnonzero(status == kernel.ROTATION_RANGE)
        if bad.size:
            raise RotationRangeError(bad, f"Simo–Reissner elements {format_ids(bad)}: an end triad is turned by more "
                                          f"than {kernel.MAX_RELATIVE_ROTATION:.4g} rad against the element's middle "
                                          "triad (refine the mesh or cut the step)")
        bad = np.flatnonzero(status == kernel.NOT_FINITE)
        if bad.size:
            raise RotationRangeError(bad, f"Simo–Reissner elements {format_ids(bad)}: non-finite energy or force")

    def _state(self, d, psi):
        d = np.asarray(d, dtype=float)
        if d.shape != (self.n_centreline_dofs,):
            raise ValueError(f"d: expected shape ({self.n_centreline_dofs},), got {d.shape}")
        psi = np.asarray(psi, dtype=float)
        if psi.shape != (self.n_rotation_nodes, 3):
            raise ValueError(f"psi: expected shape ({self.n_rotation_nodes}, 3), got {psi.shape}")
        if not (np.isfinite(d).all() and np.isfinite(psi).all()):
            raise ValueError("d or psi has NaN or infinite entries")
        padded = np.concatenate([d, np.zeros(3 * self.n_rotation_nodes)])
        return self._coefficients(padded), self._element_triads(self.triads(psi))

    def _run(self, d, psi, want):
        Dd, triads_e = self._state(d, psi)
        n_el = self.beams.n_elements
        energy = np.empty(n_el)
        fe = np.empty((n_el, kernel.N_DOFS) if want >= 1 else (0, kernel.N_DOFS))
        ke = np.empty((n_el, kernel.N_DOFS, kernel.N_DOFS) if want == 2 else (0, kernel.N_DOFS, kernel.N_DOFS))
        status = np.empty(n_el, dtype=np.int64)
        dH, lag, dlag, A0, J = self._points
        args = (dH, lag, dlag, A0, J, self._wF, self._wM, self._Gamma0, self._K0, self.CF, self.CM, Dd, triads_e,
                self._spins, want, energy, fe, ke, status)
        if n_el <= CHUNK:
            kernel.element_range(0, n_el, *args)
        else:
            kernel.element_chunks(*args)
        self._check_status(status)
        return energy, fe, ke

    #: CSR pattern of K and the map from element entries to CSR slots, built once from ``_dofs`` and
    #: ``n_dofs`` exactly as for the torsion-free beam (the element matrices are full, so the same
    #: pattern serves a non-symmetric K)
    _csr_pattern = BeamModel._csr_pattern

    # -- public ------------------------------------------------------------------------------------
    def triads(self, psi):
        """Current triads ``exp(ψ_k) Λ0_k`` (n_rotation_nodes, 3, 3) of the state ψ (n_rotation_nodes, 3)."""
        psi = np.ascontiguousarray(psi, dtype=float)
        R = np.empty((len(psi), 3, 3))
        exp_rows(psi, R)
        return np.ascontiguousarray(R @ self.triads0)

    def update(self, psi, dtheta):
        """State after the multiplicative update ``Λ ← exp(Δθ) Λ``: ``log(exp(Δθ) exp(ψ))`` per
        rotation node (n_rotation_nodes, 3), ``|ψ| ≤ π``."""
        psi = np.ascontiguousarray(psi, dtype=float)
        dtheta = np.ascontiguousarray(dtheta, dtype=float).reshape(psi.shape)
        out = np.empty_like(psi)
        compose_rows(psi, dtheta, out)
        return out

    def evaluate(self, d, psi, tangent=True):
        """Internal force and (optionally) the consistent tangent.

        Parameters
        ----------
        d : (n_centreline_dofs,) array_like
            Centreline displacement.
        psi : (n_rotation_nodes, 3) array_like
            Total rotation vectors of the triads (``Λ = exp(ψ) Λ0``).
        tangent : bool

        Returns
        -------
        f : (n_dofs,) float64
            Internal virtual work per unit variation: centreline DOFs, then 3 spin components per
            rotation node (moments).
        K : scipy.sparse.csr_matrix (n_dofs, n_dofs) or None
            ``∂f/∂(d, θ)`` with multiplicative spins (not symmetric); None if ``tangent`` is False.

        Raises
        ------
        RotationRangeError
            An element's triads are too far apart (see :data:`kernel.MAX_RELATIVE_ROTATION`).
        """
        self.n_evaluations += 1
        _, fe, ke = self._run(d, psi, 2 if tangent else 1)
        f = np.bincount(self._dofs.ravel(), weights=fe.ravel(), minlength=self.n_dofs)
        if not tangent:
            return f, None
        indptr, indices, slot, nnz = self._csr_pattern()
        data = np.bincount(slot, weights=ke.ravel(), minlength=nnz)
        K = sp.csr_matrix((data, indices, indptr), shape=(self.n_dofs, self.n_dofs))
        K.has_sorted_indices = True
        return f, K

    def energy(self, d, psi):
        """Stored energy (float)."""
        energy, _, _ = self._run(d, psi, 0)
        return float(energy.sum())

    def sample(self, d, psi, eta):
        """Current quantities per element at parameters ``eta`` (k,).

        Returns
        -------
        dict of arrays
            ``"position"``, ``"displacement"`` (n_el, k, 3); ``"triads"`` (n_el, k, 3, 3) (columns
            g1, g2, g3); elastic strains ``"Gamma"`` = Γ - Γ0 and ``"K"`` = K - K0 (n_el, k, 3, material
            frame); material resultants ``"F"``, ``"M"`` and spatial ones ``"n"`` = ΛF, ``"m"`` = ΛM
            (n_el, k, 3); ``"axial_force"`` ``n·g1`` (n_el, k); ``"curvature"`` ``√(K2² + K3²)`` of
            the current triad field (n_el, k: the bending curvature, torsion K1 left out).
        """
        eta = np.atleast_1d(np.asarray(eta, dtype=float))
        if eta.ndim != 1 or not np.isfinite(eta).all() or np.abs(eta).max() > 1.0:
            raise ValueError("eta: expected a 1D array of parameters in [-1, 1]")
        Dd, triads_e = self._state(d, psi)
        points = self._tables(eta)
        G0, K0, _ = self._strains(points, np.zeros_like(Dd), self._element_triads(self.triads0))
        Gamma, Kappa, Lam = self._strains(points, Dd, triads_e)
        H = np.ascontiguousarray(evaluate(self.beams.element_type, eta[None, :], self.beams.lengths[:, None])[..., :4])
        Q = self._coefficients(np.concatenate([self._q0, np.zeros(3 * self.n_rotation_nodes)]))
        displacement = np.einsum("egk,eki->egi", H, Dd)
        F = (Gamma - G0) * self.CF[:, None, :]
        M = (Kappa - K0) * self.CM[:, None, :]
        return {"position": np.einsum("egk,eki->egi", H, Q) + displacement, "displacement": displacement,
                "triads": Lam, "Gamma": Gamma - G0, "K": Kappa - K0, "F": F, "M": M,
                "n": np.einsum("egij,egj->egi", Lam, F), "m": np.einsum("egij,egj->egi", Lam, M),
                "axial_force": F[..., 0], "curvature": np.hypot(Kappa[..., 1], Kappa[..., 2])}

    def __repr__(self):
        return (f"SimoReissnerBeam({self.beams.n_elements} elements, {self.n_rotation_nodes} rotation nodes, "
                f"{self.n_dofs} DOFs)")


def _per_element(value, n_el, choices, name):
    """``value`` (one name or one per element) as an (n_el,) array of names of ``choices``."""
    rules = np.array([value] * n_el if isinstance(value, str) else list(value), dtype=object)
    if rules.shape != (n_el,):
        raise ValueError(f"{name}: expected one of {choices} or one per element ({n_el}), got {len(rules)}")
    bad = [k for k, r in enumerate(rules) if r not in choices]
    if bad:
        raise ValueError(f"{name} of elements {format_ids(bad)}: {rules[bad[0]]!r} is not one of {choices}")
    return rules.astype(str)


def _rules(n_gauss, force_gauss, lobatto=False):
    """Union of the Gauss rules of the moment term (``n_gauss`` points) and of each force component
    (``force_gauss``: 3 point counts), then (``lobatto``) the points of :data:`LOBATTO3`: points
    (n_p,), Gauss force weights (n_p, 3), moment weights (n_p,), and Lobatto force weights (n_p, 3)
    (None without ``lobatto``; zero at the Gauss points, as the Gauss weights are at the Lobatto
    points)."""
    counts = sorted({n_gauss, *force_gauss})
    eta = np.concatenate([gauss_legendre(n)[0] for n in counts])
    offsets = np.cumsum([0] + [n for n in counts])
    wF = np.zeros((len(eta), 3))
    wM = np.zeros(len(eta))
    for n, o in zip(counts, offsets):
        w = gauss_legendre(n)[1]
        if n == n_gauss:
            wM[o:o + n] = w
        for i in range(3):
            if force_gauss[i] == n:
                wF[o:o + n, i] = w
    if not lobatto:
        return eta, wF, wM, None
    x, w = LOBATTO3
    wL = np.vstack([np.zeros_like(wF), np.repeat(w[:, None], 3, axis=1)])
    return (np.concatenate([eta, x]), np.vstack([wF, np.zeros((3, 3))]), np.concatenate([wM, np.zeros(3)]), wL)


def _default_triads(beams):
    return reference_triads(beams)
