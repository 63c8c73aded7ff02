"""Slow, obvious reference implementations for the kernel tests.

Each function recomputes something a kernel computes, the plain way: formulas written out,
brute force over all pairs, dense sampling, scipy's general-purpose solvers and adaptive
quadrature. None of them calls a Numba kernel unless its docstring says so (then the point of
the reference is the summation or the bookkeeping around it, not the functions it evaluates).

Contents, in the order of the data path:

- numbering: LM rows and centreline columns of every beam element (docs/conventions.md §2);
- beams: centreline functions H, centrelines r(η), r'(η), arc lengths (fixed and adaptive
  Gauss), the functions as exact polynomials, multiplier functions Φ;
- solids: shape functions from a monomial basis fitted to the reference nodes, the reference
  element of any family from its face planes (distance outside, lattice samples, random points,
  exact integrals by collapsed Gauss rules on a split into tetrahedra), point location by lattice
  search and ``scipy.optimize.root``, owners in structured grids;
- search: boxes from dense sampling, brute-force box overlaps, the pairs a beam really enters;
- segmentation: the owner of densely sampled centreline points; the pieces of straight chords
  in unit-cell grids and in tets in closed form;
- operators: D, M, κ summed point by point, and by adaptive quadrature over segments; the
  constraint residual by sparse products;
- physics: quadrature rules on reference cells (tensor and collapsed Gauss) and surface loads
  (dead traction, follower pressure) face by face;
- odds and ends: central differences, splitmix64.

The numpy Newton projections of the tests are not here: they stay where they are
(tests/test_mortar.py, tests/hard_cases.py) until they are folded with the study's.
"""

import numpy as np
from numpy.polynomial import Polynomial
from scipy.integrate import quad, quad_vec
from scipy.optimize import root
from scipy.spatial import cKDTree

from mortar1d3d.elements.solid.dispatch import BY_CODE, SOLID_MODULES
from mortar1d3d.elements.solid.registry import FAMILIES

# --------------------------------------------------------------------------------------------
# numbering (docs/conventions.md §2)
# --------------------------------------------------------------------------------------------


def lm_rows(beams, n_phi):
    """LM node (row of the scalar operators) of every multiplier function, and the number of LM nodes.

    Beam nodes keep their own index (the two end nodes of each element carry Φ_0, Φ_1); the
    ``n_phi - 2`` interior LM nodes follow, element by element, after all beam nodes.

    Returns
    -------
    rows : (n_elements, n_phi) int
    n_lm : int
    """
    n_int = n_phi - 2
    rows = np.empty((beams.n_elements, n_phi), dtype=np.int64)
    for e in range(beams.n_elements):
        rows[e, 0], rows[e, 1] = beams.elements[e, 0], beams.elements[e, 1]
        for i in range(n_int):
            rows[e, 2 + i] = beams.n_nodes + n_int * e + i
    return rows, beams.n_nodes + n_int * beams.n_elements


def centreline_columns(beams):
    """Scalar column (a block of 3 DOFs) of every centreline coefficient q_k: (n_elements, n_functions).

    Hermite nodes hold [r, t] (columns 2n, 2n + 1); Lagrange nodes hold r (column n), in the
    element's node order (line3: end, end, middle).
    """
    if beams.element_type.name == "hermite":
        n1, n2 = beams.elements[:, 0], beams.elements[:, 1]
        return np.column_stack([2 * n1, 2 * n1 + 1, 2 * n2, 2 * n2 + 1])
    return np.asarray(beams.elements, dtype=np.int64).copy()


# --------------------------------------------------------------------------------------------
# beams
# --------------------------------------------------------------------------------------------
LM_NODES = {"line2": [-1.0, 1.0], "line3": [-1.0, 1.0, 0.0], "line4": [-1.0, 1.0, -1.0 / 3.0, 1.0 / 3.0]}


def beam_shape(kind, eta, L=1.0):
    """Centreline functions H_k(η) and dH_k/dη, each (n_functions, m), written out from docs/conventions.md §2.

    ``kind``: "hermite" (coefficients r1, t1, r2, t2; L enters H2, H4), "line" (r1, r2) or
    "line3" (r1, r2, r_mid).
    """
    eta = np.atleast_1d(np.asarray(eta, float))
    if kind == "hermite":
        H = [(2 - 3 * eta + eta ** 3) / 4, L / 8 * (1 - eta - eta ** 2 + eta ** 3),
             (2 + 3 * eta - eta ** 3) / 4, L / 8 * (-1 - eta + eta ** 2 + eta ** 3)]
        dH = [(-3 + 3 * eta ** 2) / 4, L / 8 * (-1 - 2 * eta + 3 * eta ** 2),
              (3 - 3 * eta ** 2) / 4, L / 8 * (-1 + 2 * eta + 3 * eta ** 2)]
    elif kind == "line":
        H, dH = [(1 - eta) / 2, (1 + eta) / 2], [-0.5 + 0 * eta, 0.5 + 0 * eta]
    else:
        H = [eta * (eta - 1) / 2, eta * (eta + 1) / 2, 1 - eta ** 2]
        dH = [eta - 0.5, eta + 0.5, -2 * eta]
    return np.array(H), np.array(dH)


def beam_functions(beams, element, eta):
    """H_k (n_functions,) of beam element ``element`` at one η (:func:`beam_shape`)."""
    return beam_shape(beams.element_type.name, eta, beams.lengths[element])[0][:, 0]


def centreline(beams, e, eta):
    """r(η) (m, 3) and r'(η) (m, 3) of beam element e, from the formulas of :func:`beam_shape`.

    Summed relative to the element's first node, so that far-from-origin coordinates keep
    their digits: the position functions sum to one and their derivatives to zero.
    """
    eta = np.atleast_1d(np.asarray(eta, float))
    nodes = beams.elements[e]
    kind = beams.element_type.name
    H, dH = beam_shape(kind, eta, beams.lengths[e])
    if kind == "hermite":
        q = [beams.positions[nodes[0]], beams.tangents[nodes[0]], beams.positions[nodes[1]], beams.tangents[nodes[1]]]
    else:
        q = list(beams.positions[nodes])
    base = q[0]
    if kind == "hermite":
        r = base + H[2][:, None] * (q[2] - base) + H[1][:, None] * q[1] + H[3][:, None] * q[3]
        dr = dH[2][:, None] * (q[2] - base) + dH[1][:, None] * q[1] + dH[3][:, None] * q[3]
    else:
        r = base + sum(Hk[:, None] * (qk - base) for Hk, qk in zip(H[1:], q[1:]))
        dr = sum(dHk[:, None] * (qk - base) for dHk, qk in zip(dH[1:], q[1:]))
    return r, dr


def arc_length(beams, e, a, b, n=40):
    """∫_a^b |r'(η)| dη of beam element e by the n-point Gauss rule (exact up to the rule's error)."""
    x, w = np.polynomial.legendre.leggauss(n)
    eta = 0.5 * (a + b) + 0.5 * (b - a) * x
    _, dr = centreline(beams, e, eta)
    return 0.5 * (b - a) * float(w @ np.linalg.norm(dr, axis=1))


def adaptive_arc_length(beams, e, a=-1.0, b=1.0):
    """∫_a^b |r'(η)| dη of beam element e by adaptive quadrature (``scipy.integrate.quad``, 1e-13)."""
    value, _ = quad(lambda x: float(np.linalg.norm(centreline(beams, e, x)[1])), a, b,
                    epsabs=0.0, epsrel=1e-13, limit=200)
    return value


def hermite_polys(L):
    """H1..H4 of docs/conventions.md §2 as numpy Polynomials in η (for exact integrals of products)."""
    return [Polynomial([2.0, -3.0, 0.0, 1.0]) / 4, Polynomial([1.0, -1.0, -1.0, 1.0]) * (L / 8),
            Polynomial([2.0, 3.0, 0.0, -1.0]) / 4, Polynomial([-1.0, -1.0, 1.0, 1.0]) * (L / 8)]


def hermite_curve(r1, t1, r2, t2, L):
    """(3,) list of Polynomials x(η), y(η), z(η) of the Hermite centreline."""
    H = hermite_polys(L)
    return [H[0] * r1[i] + H[1] * t1[i] + H[2] * r2[i] + H[3] * t2[i] for i in range(3)]


def lagrange_polys(nodes):
    """The Lagrange basis through ``nodes`` as Polynomials: p_j(nodes[m]) = δ_jm, by the product formula."""
    out = []
    for j, xj in enumerate(nodes):
        p = Polynomial([1.0])
        for m, xm in enumerate(nodes):
            if m != j:
                p = p * Polynomial([-xm, 1.0]) / (xj - xm)
        out.append(p)
    return out


_MULTIPLIERS = {lm: lagrange_polys(nodes) for lm, nodes in LM_NODES.items()}


def multiplier_values(lm, eta):
    """Φ_j(η) (n_phi,) of the multiplier type ``lm`` ("line2", "line3", "line4") at one η: the Lagrange
    basis through :data:`LM_NODES`."""
    return np.array([p(eta) for p in _MULTIPLIERS[lm]])


def integrate(p, a=-1.0, b=1.0):
    """Exact integral of a Polynomial over [a, b]."""
    q = p.integ()
    return q(b) - q(a)


# --------------------------------------------------------------------------------------------
# solids: shape functions from monomial bases fitted to the reference nodes
# --------------------------------------------------------------------------------------------
_HEX8 = [(i, j, k) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
_HEX27 = [(i, j, k) for i in range(3) for j in range(3) for k in range(3)]
# serendipity: the hex27 monomials whose "superlinear degree" (degree counting only exponents 2) fits
_HEX20 = [m for m in _HEX27 if sum(m) <= 3 or (sum(m) == 4 and max(m) == 2 and min(m) == 1)]
_TET4 = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
_TET10 = [m for m in _HEX27 if sum(m) <= 2]
_WEDGE6 = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)]    # P1(ξ1, ξ2) ⊗ P1(ζ)
_BASES = {"hexahedron": _HEX8, "hexahedron20": _HEX20, "hexahedron27": _HEX27, "tetra": _TET4, "tetra10": _TET10,
          "wedge": _WEDGE6}
_COEFFICIENTS = {}


def descriptor(name):
    """The element descriptor of the meshio type ``name``."""
    return next(d for d in BY_CODE.values() if d.name == name)


def _basis(name):
    """Integer exponents (monomials, 3) of the element's monomials and the inverse Vandermonde matrix."""
    if name not in _COEFFICIENTS:
        d = descriptor(name)
        exps = np.array(_BASES[name], dtype=float)
        assert len(exps) == d.n_nodes, name
        V = np.prod(d.reference_nodes[:, None, :] ** exps[None, :, :], axis=2)   # (nodes, monomials)
        _COEFFICIENTS[name] = (exps.astype(int), np.linalg.inv(V))                 # N = m(ξ) V⁻¹
    return _COEFFICIENTS[name]


_POWERS = np.arange(3.0)                  # exponents of ξ_i in the monomials: 0, 1 or 2
_AXES = np.arange(3)


def shape_values(name, xi):
    """N (m, n_nodes) and dN/dξ (m, n_nodes, 3) at the points ``xi`` (m, 3).

    N_a is the combination of the element's monomials that is 1 at reference node a and 0 at
    the others (the inverse Vandermonde matrix): no shape function of the library is used, so
    a wrong node order or shape function there shows.
    """
    exps, C = _basis(name)
    xi = np.asarray(xi, float)[:, :, None]
    pw = np.ascontiguousarray((xi ** _POWERS)[:, _AXES, exps])                    # (m, monomials, 3): ξ_i^e_i
    dpw = (_POWERS * xi ** np.maximum(_POWERS - 1, 0))[:, _AXES, exps]             # e_i ξ_i^(e_i - 1)
    dmono = np.empty_like(pw)
    dmono[..., 0] = dpw[..., 0] * (pw[..., 1] * pw[..., 2])
    dmono[..., 1] = dpw[..., 1] * (pw[..., 0] * pw[..., 2])
    dmono[..., 2] = dpw[..., 2] * (pw[..., 0] * pw[..., 1])
    return np.prod(pw, axis=2) @ C, np.einsum("mpi,pa->mai", dmono, C)


def linear_map_deviation(name, X, L, x_c, xi):
    """|ζ(x(ξ)) - ξ| (m, 3) at the parameters ``xi`` (m, 3) of an element with nodes ``X`` (n_nodes, 3): the
    distance per component between ξ and the parameters ζ = ξ_c + L (x - x_c) its point x(ξ) gets from the
    element's map linearised at its centre (``L`` (3, 3), ``x_c`` (3,) the rows of ``KernelInput.linear``)."""
    N, _ = shape_values(name, xi)
    return np.abs(descriptor(name).centre + (N @ X - x_c) @ L.T - xi)


def monomial_error_bound(name, X, L, radius):
    """Σ_q |(L a_q)_i| radius^|α_q| (3,): the remainder of the linearised map bounded term by term over the box
    |ξ - ξ_c|∞ <= radius, from the coefficients a_q of x(ξ) = Σ_q a_q (ξ - ξ_c)^α_q (solved from the nodes
    ``X``) over the monomials of degree >= 2."""
    d = descriptor(name)
    exps = np.array(_BASES[name], dtype=int)
    y = d.reference_nodes - d.centre
    a = np.linalg.solve(np.prod(y[:, None, :] ** exps[None, :, :], axis=2), X)
    degree = exps.sum(axis=1)
    return (np.abs(a[degree >= 2] @ L.T) * radius ** degree[degree >= 2, None]).sum(axis=0)


def solid_functions(solid, element, xi):
    """N (n_nodes,) of solid element ``element`` at ξ through the element module's njit function,
    and the element's global node ids (for :func:`operators_from_points`, which checks the sums)."""
    d = BY_CODE[int(solid.element_codes[element])]
    N = np.empty(d.n_nodes)
    SOLID_MODULES[d.name].shape.py_func(np.asarray(xi, dtype=float), N)
    return N, solid.connectivity[element, : d.n_nodes]


def family(name):
    """The :class:`~mortar1d3d.elements.descriptor.ElementFamily` called ``name`` (``"hex"``, ...)."""
    return next(f for f in FAMILIES if f.name == name)


def outside_distance(name, xi):
    """How far ξ (..., 3) lies outside the reference element of family ``name`` (<= 0 inside): the
    largest n·(ξ - o) over the face planes (origin o, outward normal n), e.g. the max norm beyond
    [-1, 1]³ on a hexahedron, the largest violated barycentric coordinate on a tetrahedron."""
    faces = family(name).faces
    xi = np.asarray(xi, float)
    return np.max(np.einsum("...i,fi->...f", xi, faces[:, 3]) - np.einsum("fi,fi->f", faces[:, 0], faces[:, 3]),
                  axis=-1)


def parameter_box(name):
    """(2, 3) lower and upper corner of the box around the reference element of family ``name``."""
    corners = family(name).corners
    return np.stack([corners.min(axis=0), corners.max(axis=0)])


def reference_samples(name, n=7):
    """The lattice of n points per direction over the box of the reference element of family
    ``name``, the points in the closed element: (m, 3) (e.g. the tensor lattice on [-1, 1]³, the
    lattice points of [0, 1]³ with ξ1 + ξ2 + ξ3 <= 1)."""
    lower, upper = parameter_box(name)
    axes = [np.linspace(lower[i], upper[i], n) for i in range(3)]
    box = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return box[outside_distance(name, box) <= 1e-15]


def random_parameters(name, rng, n, low=-np.inf, high=0.0, grow=0.0):
    """n points uniformly distributed over the part of the reference element's box (grown by ``grow``)
    where ``low <= outside_distance <= high`` (rejection sampling): by default the element itself."""
    lower, upper = parameter_box(name)
    out = np.empty((0, 3))
    while len(out) < n:
        xi = rng.uniform(lower - grow, upper + grow, (4 * n, 3))
        g = outside_distance(name, xi)
        out = np.vstack([out, xi[(g >= low) & (g <= high)]])
    return out[:n]


def _tetrahedra(name):
    """(k, 4, 3) a split of the reference element of family ``name`` into tetrahedra: its centroid
    joined to the triangles of a fan over each face (the corners of the face, ``face_nodes``)."""
    f = family(name)
    centre = f.corners.mean(axis=0)
    out = []
    for nodes in f.face_nodes:
        for k in range(1, len(nodes) - 1):
            out.append([centre, f.corners[nodes[0]], f.corners[nodes[k]], f.corners[nodes[k + 1]]])
    return np.array(out)


def domain_rule(name, n=8):
    """Points (q, 3) and weights (q,) integrating over the reference element of family ``name``: the
    collapsed n³ Gauss rule (:func:`simplex_rule`) on every tetrahedron of a split of the element,
    exact for polynomials of degree 2n - 3 (13 with n = 8)."""
    points, weights = simplex_rule(3, n)
    P, W = [], []
    for t in _tetrahedra(name):
        A = (t[1:] - t[0]).T
        P.append(t[0] + points @ A.T)
        W.append(weights * abs(np.linalg.det(A)))
    return np.vstack(P), np.concatenate(W)


def cell_owners(p, lower, h, cells):
    """Indices of the structured-box hex cells (x fastest) whose closed box contains p (1e-12 slack)."""
    nx, ny, nz = cells
    out = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                lo = np.asarray(lower) + np.array([i, j, k]) * h
                if np.all(p >= lo - 1e-12) and np.all(p <= lo + h + 1e-12):
                    out.append(i + nx * (j + ny * k))
    return out


# --------------------------------------------------------------------------------------------
# point location: lattice search, then scipy.optimize.root
# --------------------------------------------------------------------------------------------
INSIDE_TOL = 1e-9      # parameter distance outside the element still counted inside (docs/conventions.md §2)
LATTICE = 25           # lattice points per direction of the search
_LATTICES = {}


def _lattice(name):
    """Lattice ξ (g, 3) of the reference element, its spacing, N (g, n_nodes) and dN/dξ (g, n_nodes, 3)
    there, once per type."""
    if name not in _LATTICES:
        family_name = descriptor(name).family
        xi = reference_samples(family_name, LATTICE)
        spacing = np.ptp(parameter_box(family_name), axis=0).max() / (LATTICE - 1)
        _LATTICES[name] = (xi, spacing) + shape_values(name, xi)
    return _LATTICES[name]


class Element:
    """One solid element in its own frame (nodes minus the first node), for point location.

    Attributes: ``descriptor``, ``origin`` (3,), ``X`` (n_nodes, 3) relative nodes, ``h`` (the
    diagonal of the nodes' box), ``lattice`` (g, 3) ξ of the reference lattice, ``tree`` a
    k-d tree of their images x(ξ) and ``reach``, how far the nearest image can be from a point
    of the element.
    """

    def __init__(self, solid, s):
        self.descriptor = d = BY_CODE[int(solid.element_codes[s])]
        nodes = solid.points[solid.connectivity[s, : d.n_nodes]]
        self.origin = nodes[0]
        self.X = nodes - nodes[0]
        self.h = float(np.linalg.norm(self.X.max(axis=0) - self.X.min(axis=0)))
        self.lattice, spacing, N, dN = _lattice(d.name)
        self.tree = cKDTree(N @ self.X)
        # every ξ of the element has a lattice point within one lattice-cell diagonal √3·spacing
        # (a corner of its lattice cell that lies in the element), joined to it by a segment
        # inside the element, so its image is within max|J| times that; |J| is taken at the
        # lattice points (bounded by √(‖J‖₁ ‖J‖∞), the largest column sum times the largest row
        # sum), with a quarter more for the parts between them
        J = np.abs(np.matmul(self.X.T, dN))
        norm = np.sqrt(J.sum(axis=1).max(axis=1) * J.sum(axis=2).max(axis=1))
        self.reach = 1.25 * norm.max() * np.sqrt(3.0) * spacing

    def map(self, xi):
        """x(ξ) (relative to ``origin``) and J = dx/dξ at one ξ."""
        N, dN = shape_values(self.descriptor.name, np.asarray(xi, float)[None])
        return N[0] @ self.X, self.X.T @ dN[0]

    def start(self, p):
        """The lattice ξ whose image is nearest to p (relative to ``origin``), and that distance."""
        dist, nearest = self.tree.query(p)
        return self.lattice[nearest], dist

    def solve(self, p, start):
        """ξ with x(ξ) = p (p relative to ``origin``) by MINPACK's hybrid method from ``start``,
        and the relative residual |x(ξ) - p| / h."""
        def residual(xi):
            x, J = self.map(xi)
            return x - p, J
        xi = root(residual, start, jac=True, method="hybr", options={"xtol": 1e-15}).x
        return xi, float(np.linalg.norm(self.map(xi)[0] - p)) / self.h

    def locate(self, P):
        """ξ (m, 3) of the points P (m, 3, absolute coordinates) and whether each lies in the element.

        A point whose nearest lattice image is farther than ``reach`` is not in the element;
        the others are solved from that lattice point and count as inside when the residual is
        below 1e-12 h and ξ lies in the reference element up to :data:`INSIDE_TOL`.
        """
        P = np.atleast_2d(np.asarray(P, float)) - self.origin
        xi = np.full((len(P), 3), np.nan)
        inside = np.zeros(len(P), dtype=bool)
        dist, nearest = self.tree.query(P)
        for i in np.flatnonzero(dist <= self.reach):
            xi[i], res = self.solve(P[i], self.lattice[nearest[i]])
            inside[i] = res <= 1e-12 and outside_distance(self.descriptor.family, xi[i]) <= INSIDE_TOL
        return xi, inside


def solid_elements(solid):
    """An :class:`Element` for every solid element, in order."""
    return [Element(solid, s) for s in range(solid.n_elements)]


def containing(elements, P):
    """Boolean (m, n_elements): point i lies in element s (:meth:`Element.locate`, every element).

    ``elements``: :func:`solid_elements` of the mesh."""
    P = np.atleast_2d(np.asarray(P, float))
    return np.column_stack([element.locate(P)[1] for element in elements])


def owners(elements, P):
    """The lowest-index solid element containing each point (-1: none): (m,) int.

    Elements are tried in ascending order; a point leaves the search at its first owner."""
    P = np.atleast_2d(np.asarray(P, float))
    owner = np.full(len(P), -1)
    for s, element in enumerate(elements):
        todo = np.flatnonzero(owner < 0)
        owner[todo[element.locate(P[todo])[1]]] = s
    return owner


# --------------------------------------------------------------------------------------------
# search
# --------------------------------------------------------------------------------------------
def brute_force_pairs(beam_boxes, solid_boxes):
    """Boolean (n_beam, n_solid): closed boxes overlap in every coordinate."""
    return ((beam_boxes[:, None, 0, :] <= solid_boxes[None, :, 1, :]).all(axis=2)
            & (solid_boxes[None, :, 0, :] <= beam_boxes[:, None, 1, :]).all(axis=2))


def sampled_beam_boxes(beams, samples=101):
    """(n_elements, 2, 3) [min, max] of r(η) over ``samples`` equidistant η of each beam element.

    Inside the true box of the element (the points are on it), so never larger than a
    conservative box."""
    _, r = centreline_samples(beams, samples)
    return np.stack([r.min(axis=1), r.max(axis=1)], axis=1)


def sampled_solid_boxes(solid, n=11):
    """(n_elements, 2, 3) [min, max] of x(ξ) over the n-per-direction lattice of each solid element."""
    boxes = np.empty((solid.n_elements, 2, 3))
    for s in range(solid.n_elements):
        d = BY_CODE[int(solid.element_codes[s])]
        N, _ = shape_values(d.name, reference_samples(d.family, n))
        x = N @ solid.points[solid.connectivity[s, : d.n_nodes]]
        boxes[s] = x.min(axis=0), x.max(axis=0)
    return boxes


def centreline_samples(beams, samples):
    """η (samples,) equidistant on [-1, 1] and r(η) of every beam element: (n_elements, samples, 3)."""
    eta = np.linspace(-1.0, 1.0, samples)
    return eta, np.array([centreline(beams, e, eta)[0] for e in range(beams.n_elements)])


def entered_pairs(beams, solid, samples=41):
    """Boolean (n_beam_elements, n_solid_elements): a sample r(η) of the beam element lies in the
    solid element (``samples`` equidistant η per beam element, every solid element tried)."""
    _, r = centreline_samples(beams, samples)
    inside = containing(solid_elements(solid), r.reshape(-1, 3))
    return inside.reshape(beams.n_elements, samples, solid.n_elements).any(axis=1)


# --------------------------------------------------------------------------------------------
# segmentation
# --------------------------------------------------------------------------------------------
def sampled_owners(beams, solid, samples=41):
    """η (samples,) equidistant on [-1, 1] and the owner of r(η) in every beam element:
    (n_beam_elements, samples) int, -1 outside the solid (:func:`owners`)."""
    eta, r = centreline_samples(beams, samples)
    return eta, owners(solid_elements(solid), r.reshape(-1, 3)).reshape(beams.n_elements, samples)


def grid_chord_pieces(a, b, cells=(2, 2, 2)):
    """Segments [(0, owner, η_a, η_b), ...] of the straight beam element a→b (η = -1 at a) in the grid of
    unit cells from the origin (:func:`cell_owners` numbering).

    Cut where the chord crosses a grid plane (cuts closer than 1e-9 in η merged); the owner of
    each piece is the lowest-index cell containing its midpoint, and neighbouring pieces of one
    owner are joined.
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    cuts = {-1.0, 1.0}
    for i in range(3):
        if b[i] != a[i]:
            for plane in range(cells[i] + 1):
                eta = 2.0 * (plane - a[i]) / (b[i] - a[i]) - 1.0
                if -1.0 < eta < 1.0:
                    cuts.add(eta)
    merged = []
    for c in sorted(cuts):
        if not merged or c > merged[-1] + 1e-9:
            merged.append(c)
    merged[-1] = 1.0
    cuts = merged
    pieces = []
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        mid = a + (0.5 * (lo + hi) + 1.0) / 2.0 * (b - a)
        owners = cell_owners(mid, (0, 0, 0), 1.0, cells)
        assert owners
        owner = min(owners)
        if pieces and pieces[-1][1] == owner:
            pieces[-1] = (0, owner, pieces[-1][2], hi)
        else:
            pieces.append((0, owner, lo, hi))
    return pieces


def tet_chord_pieces(solid, a, b):
    """Segments [(0, tet, η_a, η_b), ...] of the straight beam element a→b in the ``tetra`` block of
    ``solid``, sorted by η_a: for each tet the η interval where all barycentric coordinates of the
    chord are >= 0 (linear in η), kept if longer than 1e-9."""
    pieces = []
    conn = solid.cells["tetra"]
    for s, nodes in enumerate(conn):
        X = solid.points[nodes]
        A = (X[1:] - X[0]).T
        # p(η) = m + η h;  λ_{1..3} = A⁻¹ (p - X0), λ_0 = 1 - Σ
        m, h = 0.5 * (a + b), 0.5 * (b - a)
        l0 = np.linalg.solve(A, m - X[0])
        l1 = np.linalg.solve(A, h)
        alpha = np.concatenate([[1 - l0.sum()], l0])
        beta = np.concatenate([[-l1.sum()], l1])
        lo, hi = -1.0, 1.0
        for al, be in zip(alpha, beta):
            if abs(be) < 1e-15:
                if al < 0:
                    lo, hi = 1.0, -1.0
            elif be > 0:
                lo = max(lo, -al / be)
            else:
                hi = min(hi, -al / be)
        if hi - lo > 1e-9:
            pieces.append((0, s, lo, hi))
    return sorted(pieces, key=lambda p: p[2])


# --------------------------------------------------------------------------------------------
# D, M, κ
# --------------------------------------------------------------------------------------------
def _scatter(beams, solid, n_phi, pieces):
    """Dense scalar D (n_lm, n_centreline_dofs / 3), M (n_lm, n_solid_nodes), κ (n_lm,) from
    ``pieces``: (beam element, solid element, κ_j (n_phi,), D_jk (n_phi, n_functions), M_ja (n_phi, n_nodes))."""
    rows, n_lm = lm_rows(beams, n_phi)
    columns = centreline_columns(beams)
    D = np.zeros((n_lm, beams.n_centreline_dofs // 3))
    M = np.zeros((n_lm, solid.n_nodes))
    kappa = np.zeros(n_lm)
    for e, s, k, De, Me in pieces:
        nodes = solid.connectivity[s, : Me.shape[1]]
        for j in range(n_phi):
            row = rows[e, j]
            kappa[row] += k[j]
            for c, value in zip(columns[e], De[j]):
                D[row, c] += value
            for a, value in zip(nodes, Me[j]):
                M[row, a] += value
    return D, M, kappa


def operators_from_points(beams, solid, ops):
    """Scalar D (dense), M (dense) and κ summed point by point from ``ops.points`` (docs/conventions.md §1).

    Checks the assembly (grouping, scatter, DOF order), not the functions: H from
    :func:`beam_shape`, N from the element modules (:func:`solid_functions`).
    """
    lm = ops.lm

    def pieces():
        for p in ops.points:
            e, s, w = int(p["beam_element"]), int(p["solid_element"]), p["weight"]
            Phi = multiplier_values(lm, p["eta"])
            H = beam_functions(beams, e, p["eta"])
            N, _ = solid_functions(solid, s, p["xi"])
            yield e, s, Phi * w, np.outer(Phi, H) * w, np.outer(Phi, N) * w

    return _scatter(beams, solid, len(LM_NODES[lm]), pieces())


def constraint_residual(ops, q, x):
    """‖D q − M x‖ / ‖D q‖ with scipy products and numpy norms (the library uses its own kernel)."""
    Dq = ops.D @ q
    return np.linalg.norm(Dq - ops.M @ x) / np.linalg.norm(Dq)


def segment_integrals(beams, element, e, a, b, lm="line2", epsrel=1e-13):
    """κ_j, D_jk, M_ja of beam element e on [a, b] in the solid :class:`Element` ``element`` by
    adaptive quadrature.

    ``scipy.integrate.quad_vec`` of Φ_j [1, H_k, N_a(ξ(η))] |r'(η)| over η ∈ [a, b]
    (ds = |r'(η)| dη on the reference centreline); ξ(η) solves x(ξ) = r(η) in the element by
    ``scipy.optimize.root`` (:meth:`Element.solve`) from the nearest ξ found so far; N from
    :func:`shape_values`. Nothing of the library's kernels is evaluated.

    Returns
    -------
    kappa : (n_phi,), D : (n_phi, n_functions), M : (n_phi, n_nodes)
    """
    kind = beams.element_type.name
    L = beams.lengths[e]
    n_phi = len(LM_NODES[lm])
    n_f = beams.element_type.n_functions

    solved = {}          # η -> ξ found so far: the nearest one starts the next solve

    def integrand(eta):
        r, dr = centreline(beams, e, eta)
        p = r[0] - element.origin
        start = solved[min(solved, key=lambda t: abs(t - eta))] if solved else element.start(p)[0]
        xi, res = element.solve(p, start)
        # the segment lies in its element: a solution outside would be a fold of the extended map
        assert res <= 1e-12 and outside_distance(element.descriptor.family, xi) <= INSIDE_TOL, (e, eta, xi, res)
        solved[eta] = xi
        N, _ = shape_values(element.descriptor.name, xi[None])
        phi = multiplier_values(lm, eta) * np.linalg.norm(dr[0])
        H = beam_shape(kind, eta, L)[0][:, 0]
        return np.concatenate([phi, np.outer(phi, H).ravel(), np.outer(phi, N[0]).ravel()])

    values, _ = quad_vec(integrand, a, b, epsabs=0.0, epsrel=epsrel, norm="max", limit=400)
    return (values[:n_phi], values[n_phi:n_phi * (1 + n_f)].reshape(n_phi, n_f),
            values[n_phi * (1 + n_f):].reshape(n_phi, -1))


def adaptive_operators(beams, solid, segments, lm="line2", epsrel=1e-13):
    """Scalar D, M (dense) and κ from :func:`segment_integrals` over every row of ``segments``
    (structured array with beam_element, solid_element, eta_start, eta_end)."""
    elements = {}

    def pieces():
        for row in segments:
            e, s = int(row["beam_element"]), int(row["solid_element"])
            if s not in elements:
                elements[s] = Element(solid, s)
            yield (e, s) + segment_integrals(beams, elements[s], e, row["eta_start"], row["eta_end"], lm, epsrel)

    return _scatter(beams, solid, len(LM_NODES[lm]), pieces())


# --------------------------------------------------------------------------------------------
# quadrature rules and surface loads
# --------------------------------------------------------------------------------------------
def cube_rule(dim, n):
    """The tensor n-point Gauss rule on [-1, 1]^dim: points (n^dim, dim), first coordinate slowest,
    and weights (n^dim,)."""
    x, w = np.polynomial.legendre.leggauss(n)
    points = np.stack(np.meshgrid(*[x] * dim, indexing="ij"), axis=-1).reshape(-1, dim)
    weights = np.prod(np.stack(np.meshgrid(*[w] * dim, indexing="ij"), axis=-1).reshape(-1, dim), axis=1)
    return points, weights


def simplex_rule(dim, n):
    """The collapsed (Duffy) n^dim Gauss rule on the unit simplex x >= 0, Σx <= 1 (dim 2 or 3).

    Gauss points s ∈ [0, 1]^dim map to x_1 = s_1, x_k = s_k Π_{j<k} (1 - s_j), whose Jacobian
    Π_{j<dim} (1 - s_j)^(dim - j) joins the weights: exact for polynomials of degree 2n - dim.
    """
    g, gw = cube_rule(dim, n)
    s, weights = (g + 1.0) / 2.0, gw / 2.0 ** dim
    points = s.copy()
    for k in range(1, dim):
        points[:, k] = s[:, k] * np.prod(1.0 - s[:, :k], axis=1)
        weights = weights * (1.0 - s[:, k - 1]) ** (dim - k)
    return points, weights


def face_rule(shape, n=5):
    """[(u, v, w), ...] on a face of shape ``shape`` (a face shape's name): the n × n Gauss rule on
    the square ``"quadrilateral"`` or the collapsed one on the ``"triangle"`` u, v >= 0, u + v <= 1."""
    points, weights = {"quadrilateral": cube_rule, "triangle": simplex_rule}[shape](2, n)
    return [(u, v, w) for (u, v), w in zip(points, weights)]


def surface_loads(solid, faces, u, t, p):
    """Nodal forces (3 n_nodes,) of the dead traction ``t`` (3,) per reference area and of the follower
    pressure ``p`` on the current configuration X + u, face by face.

    ``faces``: rows (element, local face, type code) as ``physics.surface.boundary_faces`` lists
    them. All volume shape functions of the element (its module's njit functions) at the points
    of :func:`face_rule` (5 × 5) on the face ξ = origin + u a + v b of the descriptor, no
    tabulation: traction ∫ N t dA0, pressure -p ∫ N n da with n da = x_,u × x_,v turned outward.
    """
    traction, pressure = np.zeros(solid.points.shape), np.zeros(solid.points.shape)
    for element, f, code in faces.tolist():
        d = BY_CODE[code]
        module = SOLID_MODULES[d.name]
        nodes = solid.connectivity[element, : d.n_nodes]
        X = solid.points[nodes]
        x = X + u[nodes]
        origin, a, b, normal = d.faces[f]
        for uq, vq, w in face_rule(d.family_type.face_shapes[f].name):
            xi = origin + uq * a + vq * b
            N, dN = np.empty(d.n_nodes), np.empty((d.n_nodes, 3))
            module.shape.py_func(xi, N)
            module.deriv.py_func(xi, dN)
            J0, J = X.T @ dN, x.T @ dN
            dA0 = np.linalg.norm(np.cross(J0 @ a, J0 @ b))
            n_da = np.cross(J @ a, J @ b)
            # orient by the physical outward normal of the (valid) reference element
            if np.cross(J0 @ a, J0 @ b) @ (np.linalg.inv(J0).T @ normal) < 0:
                n_da = -n_da
            traction[nodes] += w * dA0 * np.outer(N, t)
            pressure[nodes] += -p * w * np.outer(N, n_da)
    return traction.ravel(), pressure.ravel()


# --------------------------------------------------------------------------------------------
# odds and ends
# --------------------------------------------------------------------------------------------
def central_differences(fun, x, h):
    """(len(x), ...) rows (fun(x + h e_i) - fun(x - h e_i)) / 2h: the derivative of ``fun`` along each
    coordinate, to O(h²)."""
    out = []
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = h
        out.append((fun(x + e) - fun(x - e)) / (2.0 * h))
    return np.array(out)


def reference_splitmix64(seed, count):
    """Textbook splitmix64 with Python big ints, masked to 64 bits after every operation."""
    mask = (1 << 64) - 1
    state = seed & mask
    out = []
    for _ in range(count):
        state = (state + 0x9E3779B97F4A7C15) & mask
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & mask
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & mask
        z = z ^ (z >> 31)
        out.append(z)
    return out


# --------------------------------------------------------------------------------------------
# finite rotations (the Simo–Reissner beam's rotation maps, the plain way)

def skew_matrix(v):
    """[v]× written out."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation_exp(psi):
    """exp([ψ]×) by scipy's general matrix exponential (no Rodrigues formula)."""
    from scipy.linalg import expm
    return expm(skew_matrix(np.asarray(psi, dtype=float)))


def rotation_log(R):
    """Rotation vector of R from its angle (arccos of the trace) and axis (skew part, or the
    eigenvector of eigenvalue 1 near π): valid for angles in (0, π]."""
    R = np.asarray(R, dtype=float)
    angle = np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    if angle < 1e-12:
        return np.zeros(3)
    if angle < np.pi - 1e-3:
        w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
        return angle * w / (2.0 * np.sin(angle))
    values, vectors = np.linalg.eig(R)
    axis = np.real(vectors[:, np.argmin(np.abs(values - 1.0))])
    axis /= np.linalg.norm(axis)
    # the sign of the axis: the one whose rotation by ``angle`` reproduces R better
    candidates = [axis * angle, -axis * angle]
    return min(candidates, key=lambda p: np.abs(rotation_exp(p) - R).max())


def spin_jacobian(psi, h=1e-6):
    """T(ψ) with δR Rᵀ = [T δψ]×, by central differences of :func:`rotation_exp`."""
    psi = np.asarray(psi, dtype=float)
    R = rotation_exp(psi)
    T = np.empty((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        W = (rotation_exp(psi + e) - rotation_exp(psi - e)) / (2.0 * h) @ R.T
        T[:, j] = [W[2, 1], W[0, 2], W[1, 0]]
    return T


# --------------------------------------------------------------------------------------------
# NURBS solids (issue 19): the exact cylinder sector and the patch functions by Cox–de Boor
# --------------------------------------------------------------------------------------------
def in_sector(x, r_inner, r_outer, angle, height):
    """Whether points x (n, 3) lie in the hollow cylinder sector 0 <= θ <= angle (degrees),
    r_inner <= r <= r_outer, 0 <= z <= height (the exact set a NURBS pipe generator represents)."""
    x = np.atleast_2d(x)
    r = np.hypot(x[:, 0], x[:, 1])
    theta = np.degrees(np.arctan2(x[:, 1], x[:, 0]))
    theta = np.where(theta < -1e-12, theta + 360.0, theta)
    return (r >= r_inner) & (r <= r_outer) & (theta <= angle) & (x[:, 2] >= 0.0) & (x[:, 2] <= height)


def indicator_crossings(curve, inside, n=4001, tol=1e-15):
    """Parameters η ∈ (-1, 1) where ``inside(curve(η))`` changes: dense sampling, then bisection of
    each change to ``tol``; ``curve`` maps (k,) η to (k, 3) points."""
    eta = np.linspace(-1.0, 1.0, n)
    flag = inside(curve(eta))
    out = []
    for k in np.flatnonzero(flag[1:] != flag[:-1]):
        a, b = eta[k], eta[k + 1]
        fa = flag[k]
        while b - a > tol:
            m = 0.5 * (a + b)
            if inside(curve(np.array([m])))[0] == fa:
                a = m
            else:
                b = m
        out.append(0.5 * (a + b))
    return np.array(out)


def nurbs_functions(patch, element, xi):
    """Values (n_control,) of all NURBS functions of ``patch`` at the parameters ``xi`` of its element
    ``element`` (last direction fastest), by Cox–de Boor over the knot vectors (no extraction)."""
    from mortar1d3d.nurbs.knots import bspline_values

    span = np.unravel_index(element, patch.element_shape)
    values = []
    for d in range(3):
        U, p = patch.knots[d], patch.degrees[d]
        distinct = np.unique(U)
        lo, hi = distinct[span[d]], distinct[span[d] + 1]
        values.append(bspline_values(U, p, [lo + 0.5 * (xi[d] + 1.0) * (hi - lo)])[0])
    N = np.einsum("i,j,k->ijk", *values) * patch.weights
    return (N / N.sum()).ravel()
