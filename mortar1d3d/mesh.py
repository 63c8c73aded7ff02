"""Validated meshes: :class:`SolidMesh` (3D elements) and :class:`BeamMesh` (beam centrelines).

Inputs are checked here, once; kernels downstream assume valid data.
"""
import warnings

import numpy as np

from ._config import njit
from .elements.beam import BEAM_ELEMENTS, MAX_FUNCTIONS, beam_element
from .elements.beam import evaluate as _beam_functions
from .elements.solid.dispatch import N_NODES, NODAL_ELEMENTS, solid_element
from .elements.validity import DEGENERATE, FOLDED, INVERTED, jacobian_validity
from .errors import MeshError, format_ids
from .quadrature import gauss_legendre

# cell types of lower dimension that a volume mesh file may carry (boundary markers)
_LOWER_DIMENSIONAL = {"vertex", "line", "line3", "triangle", "triangle6", "quad", "quad8", "quad9"}


def _as_points(points, what):
    try:
        arr = np.ascontiguousarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{what}: cannot convert to a float array ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise MeshError(f"{what}: expected shape (n, 3), got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise MeshError(f"{what}: NaN or infinite coordinates at rows {format_ids(bad)}")
    return arr


def _as_connectivity(cells, n_per_cell, n_points, what):
    try:
        arr = np.asarray(cells)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{what}: expected an (m, {n_per_cell}) integer array ({exc})") from None
    if arr.ndim != 2 or arr.shape[1] != n_per_cell:
        raise MeshError(f"{what}: expected shape (m, {n_per_cell}), got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        if not (np.isfinite(arr).all() and np.all(arr == np.round(arr))):
            raise MeshError(f"{what}: node ids must be integers")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    bad = np.flatnonzero(((arr < 0) | (arr >= n_points)).any(axis=1))
    if bad.size:
        raise MeshError(f"{what}: node ids out of range [0, {n_points}) in elements {format_ids(bad)}")
    repeated = np.flatnonzero((np.diff(np.sort(arr, axis=1), axis=1) == 0).any(axis=1)) if n_per_cell > 1 else []
    if len(repeated):
        raise MeshError(f"{what}: elements {format_ids(repeated)} use the same node twice")
    return arr


class SolidMesh:
    """A 3D mesh of solid elements (meshio names, VTK node order), possibly of mixed types.

    Parameters
    ----------
    points : (n_nodes, 3) array_like of float
    cells : dict
        ``{meshio_type: (m, n_nodes_per_element) int array}``, e.g. ``{"hexahedron": cells}``.
        Elements are numbered block by block in the dict's order.
    weights : (n_nodes,) array_like of float, optional
        Positive node weights, required by rational element types (``nurbs27``: the nodes are
        Bézier control points; :func:`mortar1d3d.nurbs.bezier_mesh` builds such meshes from NURBS
        patches) and ignored by the others.

    Raises
    ------
    MeshError
        Unknown element type, wrong shapes, NaN/inf coordinates, node ids out of range,
        inverted, folded or degenerate elements (det J not > 1e-12 h^3 everywhere in the element,
        proved with Bernstein bounds of det J, not only at sample points).
    """

    def __init__(self, points, cells, *, point_sets=None, weights=None):
        self.points = _as_points(points, "solid points")
        if not isinstance(cells, dict) or not cells:
            raise MeshError("solid cells: expected a non-empty dict {meshio_type: connectivity}")
        self.blocks = []
        for name, conn in cells.items():
            try:
                descriptor = solid_element(name)
            except ValueError as exc:
                raise MeshError(str(exc)) from None
            conn = _as_connectivity(conn, descriptor.n_nodes, len(self.points), f"solid cells {name!r}")
            self.blocks.append((descriptor, conn))
        self.n_elements = sum(len(c) for _, c in self.blocks)
        if self.n_elements == 0:
            raise MeshError("solid mesh has no elements")
        self.element_codes = np.concatenate([np.full(len(c), d.code, np.int64) for d, c in self.blocks])
        # as wide as this mesh's largest element (not the registry's MAX_NODES): the kernels read
        # connectivity[e, :n_nodes(code)] only, and a wide rational type must not widen every mesh
        self.connectivity = np.full((self.n_elements, max(d.n_nodes for d, _ in self.blocks)), -1, dtype=np.int64)
        start = 0
        for d, c in self.blocks:
            self.connectivity[start:start + len(c), : d.n_nodes] = c
            start += len(c)
        self.point_sets = dict(point_sets or {})
        self.weights = None
        if any(d.rational for d, _ in self.blocks) or weights is not None:
            self.weights = self._check_weights(weights)
        self._kernel_points = None
        self._check_jacobians()

    def _check_weights(self, weights):
        rational = ", ".join(d.name for d, _ in self.blocks if d.rational)
        if weights is None:
            raise MeshError(f"solid weights: {rational} elements need one weight per node (weights=...)")
        try:
            w = np.ascontiguousarray(weights, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MeshError(f"solid weights: cannot convert to a float array ({exc})") from None
        if w.shape != (self.n_nodes,):
            raise MeshError(f"solid weights: expected shape ({self.n_nodes},), got {w.shape}")
        bad = np.flatnonzero(~(np.isfinite(w) & (w > 0.0)))
        if bad.size:
            raise MeshError(f"solid weights: must be finite and > 0, not at nodes {format_ids(bad)}")
        return w

    @property
    def kernel_points(self):
        """What the geometry kernels read as node coordinates: ``points`` (n_nodes, 3), or with rational
        elements (n_nodes, 4) with the weights in column 3."""
        if self.weights is None:
            return self.points
        if self._kernel_points is None:
            self._kernel_points = np.ascontiguousarray(np.column_stack([self.points, self.weights]))
        return self._kernel_points

    @property
    def n_nodes(self):
        return len(self.points)

    @property
    def cells(self):
        """``{meshio_type: connectivity}`` as given."""
        return {d.name: c for d, c in self.blocks}

    def _check_jacobians(self):
        """MeshError naming the elements whose det J is not positive throughout (a bound that cannot
        miss a fold between sample points: :mod:`mortar1d3d.elements.validity`)."""
        start = 0
        for d, conn in self.blocks:
            X = self.points[conn]
            h = np.linalg.norm(X.max(axis=1) - X.min(axis=1), axis=1)
            ids = np.arange(start, start + len(conn))
            outcome = jacobian_validity(d, X, h, None if self.weights is None else self.weights[conn])
            outcome[h == 0.0] = DEGENERATE
            for kind, text in ((INVERTED, "inverted {} elements (negative Jacobian determinant at a corner; "
                                          "check the VTK node order)"),
                               (FOLDED, "folded {} elements (det J <= 0 inside the element, > 0 at its corners: "
                                        "a mid-side node too far from the middle of its edge or face)"),
                               (DEGENERATE, "degenerate {} elements (zero Jacobian determinant)")):
                bad = outcome == kind
                if bad.any():
                    raise MeshError(f"{text.format(d.name)}: {format_ids(ids[bad])}")
            start += len(conn)

    @classmethod
    def from_meshio(cls, mesh):
        """Build from a :class:`meshio.Mesh`; 3D cell blocks of the same type are joined.

        Lower-dimensional cells (boundary triangles, lines, ...) are not part of the solid and
        are skipped with a warning that names them; unsupported 3D types raise.
        """
        cells, skipped = {}, {}
        for block in mesh.cells:
            if block.type in NODAL_ELEMENTS:
                cells.setdefault(block.type, []).append(np.asarray(block.data))
            elif block.type in _LOWER_DIMENSIONAL:
                skipped[block.type] = skipped.get(block.type, 0) + len(block.data)
            else:
                raise MeshError(f"unsupported cell type {block.type!r} in meshio mesh; supported solid "
                                f"types: {', '.join(NODAL_ELEMENTS)}")
        if skipped:
            warnings.warn("SolidMesh.from_meshio: skipped lower-dimensional cells "
                          + ", ".join(f"{n} {t}" for t, n in skipped.items()), stacklevel=2)
        if not cells:
            raise MeshError("meshio mesh has no supported 3D cells")
        return cls(mesh.points, {t: np.vstack(b) for t, b in cells.items()},
                   point_sets=getattr(mesh, "point_sets", None))

    def to_meshio(self):
        import meshio
        return meshio.Mesh(self.points, [(d.name, c) for d, c in self.blocks])

    def element_nodes(self, element):
        """Node ids of element ``element`` (global number)."""
        return self.connectivity[element, : N_NODES[self.element_codes[element]]]

    def __repr__(self):
        kinds = ", ".join(f"{len(c)} {d.name}" for d, c in self.blocks)
        return f"SolidMesh({self.n_nodes} nodes; {kinds})"


def hermite_lengths(positions, tangents, elements, rtol=1e-14, max_iterations=50):
    """Arc-length element lengths L of Hermite elements: the fixed point ``L = ∫|r'(η; L)| dη``.

    Solved by Newton's method on ``g(L) = ∫|r'(η; L)| dη - L`` with a 10-point Gauss rule,
    starting from the chord. Returns (m,) float64. Raises :class:`MeshError` naming the
    elements for which no positive length is found.
    """
    x, w = gauss_legendre(10)
    dH = np.array([[0.75 * (e * e - 1.0), 0.125 * (-1 - 2 * e + 3 * e * e),
                    0.75 * (1.0 - e * e), 0.125 * (-1 + 2 * e + 3 * e * e)] for e in x])   # dH2, dH4 per unit L
    r1, r2 = positions[elements[:, 0]], positions[elements[:, 1]]
    t1, t2 = tangents[elements[:, 0]], tangents[elements[:, 1]]
    A = dH[:, 2, None, None] * (r2 - r1)      # dH1 = -dH3: differences keep L translation invariant
    B = dH[:, 1, None, None] * t1 + dH[:, 3, None, None] * t2
    L = np.linalg.norm(r2 - r1, axis=1)
    converged = np.zeros(len(L), dtype=bool)
    for _ in range(max_iterations):
        d = A + L[None, :, None] * B
        speed = np.linalg.norm(d, axis=2)
        g = w @ speed - L
        dg = w @ (np.einsum("qmi,qmi->qm", d, B) / np.where(speed > 0, speed, 1.0)) - 1.0
        step = np.where(converged, 0.0, g / dg)
        L = L - step
        converged |= np.abs(step) <= rtol * np.abs(L)
        if converged.all():
            break
    bad = np.flatnonzero(~converged | ~(L > 0) | ~np.isfinite(L))
    if bad.size:
        raise MeshError(f"Hermite elements {format_ids(bad)}: no arc-length element length found "
                        "(tangents inconsistent with the node positions?)")
    return L


def zero_length_elements(positions, elements):
    """Ids of beam elements whose end nodes (columns 0 and 1) coincide: chord <= 1e-14 of the
    coordinates' scale (extent or magnitude, so that an offset of 1e6 does not hide it)."""
    positions = np.asarray(positions, dtype=np.float64)
    chord = np.linalg.norm(positions[elements[:, 1]] - positions[elements[:, 0]], axis=1)
    scale = np.ptp(positions, axis=0).max() if len(positions) > 1 else 0.0
    return np.flatnonzero(chord <= 1e-14 * max(scale, np.abs(positions).max(), 1e-300))


class BeamMesh:
    """Beam centrelines: cubic Hermite (positions + unit tangents) or Lagrange ``line``/``line3``.

    Use the constructors :meth:`hermite`, :meth:`lagrange` and :meth:`from_curve`.

    Attributes
    ----------
    element_type : BeamElementType
    positions : (n_nodes, 3) float64
    tangents : (n_nodes, 3) float64 unit vectors, or None for Lagrange beams
    elements : (n_elements, n_nodes_per_element) int64
    lengths : (n_elements,) float64 reference arc lengths (the Hermite ``L``)
    """

    def __init__(self, element_type, positions, elements, tangents=None):
        try:
            self.element_type = beam_element(element_type)
        except ValueError as exc:
            raise MeshError(str(exc)) from None
        self.positions = _as_points(positions, "beam positions")
        self.elements = _as_connectivity(elements, self.element_type.n_nodes, len(self.positions),
                                         f"beam elements ({self.element_type.name})")
        if len(self.elements) == 0:
            raise MeshError("beam mesh has no elements")
        short = zero_length_elements(self.positions, self.elements)
        if short.size:
            raise MeshError(f"zero-length beam elements: {format_ids(short)}")
        if self.element_type.has_tangents:
            if tangents is None:
                raise MeshError("Hermite beams need one tangent per node")
            t = _as_points(tangents, "beam tangents")
            if t.shape != self.positions.shape:
                raise MeshError(f"beam tangents: expected shape {self.positions.shape}, got {t.shape}")
            norm = np.linalg.norm(t, axis=1)
            used = np.unique(self.elements)
            zero = used[norm[used] <= 1e-12 * max(norm.max(), 1e-300)]
            if zero.size or norm.max() == 0:
                raise MeshError(f"zero beam tangents at nodes {format_ids(zero)}")
            norm[norm == 0] = 1.0
            if np.abs(norm[used] - 1.0).max() > 1e-10:
                warnings.warn("beam tangents were not unit vectors and have been normalised "
                              "(Hermite centrelines use unit tangents, docs/conventions.md §2)", stacklevel=3)
            self.tangents = np.ascontiguousarray(t / norm[:, None])
            self.lengths = hermite_lengths(self.positions, self.tangents, self.elements)
        else:
            if tangents is not None:
                raise MeshError(f"{self.element_type.name} beams take no tangents")
            self.tangents = None
            self.lengths = self._lagrange_lengths()

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def hermite(cls, positions, tangents, elements):
        """Cubic Hermite beams. ``elements``: (n, 2) node ids; one unit tangent per node."""
        return cls("hermite", positions, elements, tangents=tangents)

    @classmethod
    def lagrange(cls, positions, elements, element="line"):
        """Lagrange beams, ``element`` = ``"line"`` (n, 2) or ``"line3"`` (n, 3: ends, then middle), or
        any other registered centreline type interpolating positions only."""
        lagrange = [name for name, et in BEAM_ELEMENTS.items() if not any(et.function_offset)]
        if element not in lagrange:
            raise MeshError(f"unknown Lagrange beam element {element!r}; use {' or '.join(map(repr, lagrange))}")
        return cls(element, positions, elements)

    @classmethod
    def from_curve(cls, f, df, t0, t1, n_elements):
        """Hermite beam interpolating a parametric curve ``f(t)`` with derivative ``df(t)``.

        Nodes at ``n_elements + 1`` equally spaced parameters in ``[t0, t1]``; the tangents are
        ``df/|df|``.
        """
        n_elements = int(n_elements)
        if n_elements < 1:
            raise MeshError(f"from_curve: n_elements must be >= 1, got {n_elements}")
        t = np.linspace(t0, t1, n_elements + 1)
        positions = np.array([np.asarray(f(ti), dtype=float).reshape(3) for ti in t])
        tangents = np.array([np.asarray(df(ti), dtype=float).reshape(3) for ti in t])
        norm = np.linalg.norm(tangents, axis=1)
        if not (np.isfinite(norm).all() and (norm > 0).all()):
            raise MeshError("from_curve: df(t) is zero or not finite at some node")
        tangents /= norm[:, None]
        elements = np.column_stack([np.arange(n_elements), np.arange(1, n_elements + 1)])
        return cls.hermite(positions, tangents, elements)

    @classmethod
    def join(cls, meshes):
        """One mesh holding several beams of the same element type (node and element ids shift)."""
        meshes = list(meshes)
        kinds = {m.element_type.name for m in meshes}
        if len(kinds) != 1:
            raise MeshError(f"cannot join beams of different element types {sorted(kinds)}")
        offsets = np.cumsum([0] + [m.n_nodes for m in meshes[:-1]])
        positions = np.vstack([m.positions for m in meshes])
        elements = np.vstack([m.elements + o for m, o in zip(meshes, offsets)])
        tangents = np.vstack([m.tangents for m in meshes]) if meshes[0].element_type.has_tangents else None
        return cls(kinds.pop(), positions, elements, tangents=tangents)

    # -- derived data -------------------------------------------------------------------------
    @property
    def n_nodes(self):
        return len(self.positions)

    @property
    def n_elements(self):
        return len(self.elements)

    @property
    def n_centreline_dofs(self):
        return self.element_type.dofs_per_node * self.n_nodes

    @property
    def length(self):
        """Total reference length of all beam elements."""
        return float(self.lengths.sum())

    def centreline_dofs(self):
        """Reference centreline DOF vector q_B (docs/conventions.md §2 layout)."""
        if self.tangents is not None:
            # [r_0, t_0, r_1, t_1, ...]: two strided copies (a compiled parallel loop cost a first run
            # about a second of compiling for what is one pass over the nodes, once per model)
            q = np.empty((self.n_nodes, 2, 3))
            q[:, 0] = self.positions
            q[:, 1] = self.tangents
            return q.reshape(-1)
        return self.positions.ravel().copy()

    def coefficients(self, elements=None):
        """Vector coefficients ``q_k`` of ``r(η) = Σ H_k q_k`` per element: (m, MAX_FUNCTIONS, 3), zero-padded.

        ``elements``: optional element ids (default: all).
        """
        e = self.elements if elements is None else self.elements[np.atleast_1d(elements)]
        et = self.element_type
        Q = np.zeros((len(e), MAX_FUNCTIONS, 3))
        for k, (node, offset) in enumerate(zip(et.function_node, et.function_offset)):
            Q[:, k] = (self.tangents if offset else self.positions)[e[:, node]]
        return Q

    def function_columns(self):
        """(m, 4) scalar column index c of every coefficient (DOFs 3c..3c+2); -1 where unused."""
        et = self.element_type
        cols = np.empty((self.n_elements, 4), dtype=np.int64)
        _function_columns(self.elements, et.dofs_per_node // 3, np.array(et.function_node, dtype=np.int64),
                          np.array(et.function_offset, dtype=np.int64) // 3, cols)
        return cols

    def _lagrange_lengths(self):
        x, w = gauss_legendre(10)
        Q = self.coefficients()
        et = self.element_type
        if et.degree == 1:                                  # straight: the chord
            return np.linalg.norm(Q[:, 1] - Q[:, 0], axis=1)
        n = et.n_functions
        dH = np.ascontiguousarray(_beam_functions(et, x, derivative=True)[:, :n])   # (q, n)
        d = np.einsum("qk,mki->qmi", dH, Q[:, :n])
        return w @ np.linalg.norm(d, axis=2)

    def evaluate(self, element, eta):
        """Reference centreline positions r(η) of one element at parameters ``eta``: (len(eta), 3)."""
        eta = np.atleast_1d(np.asarray(eta, dtype=float))
        Q = self.coefficients(element)[0]
        L = self.lengths[element]
        return _beam_functions(self.element_type, eta, L) @ Q

    def __repr__(self):
        return (f"BeamMesh({self.element_type.name}: {self.n_nodes} nodes, {self.n_elements} elements, "
                f"length {self.length:.6g})")


@njit
def _function_columns(elements, per_node, function_node, function_column, cols):
    for e in range(elements.shape[0]):
        for k in range(4):
            cols[e, k] = -1
        for k in range(function_node.shape[0]):
            cols[e, k] = per_node * elements[e, function_node[k]] + function_column[k]


__all__ = ["SolidMesh", "BeamMesh", "MeshError", "hermite_lengths", "BEAM_ELEMENTS"]
