"""From NURBS patches to the engine: a mesh of rational Bézier elements and the map to control points.

Every NURBS element becomes the rational Bézier element type of the solid's common degree p
(``nurbs27`` for p = 2, ``nurbs64`` for p = 3, ``nurbs125`` for p = 4: :mod:`mortar1d3d.elements.solid.bezier_hex`): its
(p+1)³ Bézier control points and weights from Bézier extraction, in the type's node order. A patch
of lower degree in some direction (1 … 4 per direction, mixed across directions and patches) is
degree-elevated span by span to p (:func:`~mortar1d3d.nurbs.knots.bernstein_elevation`): exact, the
same rational functions and geometry in a larger Bernstein basis; p is the smallest registered
degree that is at least every patch's highest (:func:`common_degree`). Bézier
points that coincide (same position and weight: the shared faces, edges and corners of neighbouring
elements, which are the same rational functions there) are one mesh node. The NURBS functions are
combinations of the Bézier ones, R_i = Σ_a E_ia R^b_a, so anything the engine or the model computes
on the Bézier mesh maps to the control points by the sparse matrix ``T`` (n_mesh_nodes, n_control):

    node values = T @ control-point values,   M_control = M_mesh (T ⊗ I₃),   K_control = Tᵀ K_mesh T

(the mesh's nodes are ``T @ control``, so the constraint residual D q_B - M X_S is the same in both).
The control points stay the patches' own (a degree-1 direction keeps its linear space of
control-point values; only its elements are written at the higher degree).
"""
import numpy as np
import scipy.sparse as sp

from ..elements.solid.bezier_hex import tensor_order
from ..elements.solid.dispatch import SOLID_ELEMENTS
from ..elements.solid.hex_family import QUADRATIC_NODES
from ..mesh import SolidMesh
from ..physics.rational_surface import polynomial_values, rational_values
from .patch import NurbsSolid, merge_coincident

#: the rational Bézier hexahedron of each degree (all three directions alike), from the registry
BEZIER_TYPES = {d.degree: d for d in SOLID_ELEMENTS.values() if d.rational and d.family == "hex"}


def bezier_type(degrees, what="patches"):
    """The rational Bézier element type of patches of ``degrees`` (per direction, or a list of such triples
    for several patches): the registered type of :func:`common_degree`. ValueError naming ``what``
    otherwise."""
    return BEZIER_TYPES[common_degree(degrees, what)]


def common_degree(degrees, what="patches"):
    """The degree of the elements a solid's patches become: the smallest registered rational Bézier
    degree (2: ``nurbs27``, 3: ``nurbs64``, 4: ``nurbs125``) that is at least every given degree.

    Parameters
    ----------
    degrees : (3,) ints, or a list of (3,) ints (one triple per patch)
    what : str
        Named in the error (``patches`` gives ``patches[k]`` for the k-th triple).

    Raises ValueError naming the patch and direction for a degree below 1 or above the highest
    registered one (the supported degrees are 1 … max, each elevated exactly).
    """
    triples = [tuple(degrees)] if np.ndim(degrees) == 1 else [tuple(t) for t in degrees]
    top = max(BEZIER_TYPES)
    for k, triple in enumerate(triples):
        name = what if len(triples) == 1 and np.ndim(degrees) == 1 else f"{what}[{k}]"
        for d, p in enumerate(triple):
            if not 1 <= int(p) <= top:
                raise ValueError(f"{name}: degree {int(p)} in direction {d}; supported are degrees 1 to {top} per "
                                 f"direction, elevated exactly to the element types "
                                 f"{', '.join(f'{t.name} (degree {q})' for q, t in sorted(BEZIER_TYPES.items()))}")
    highest = max(max(int(p) for p in t) for t in triples)
    return min(q for q in BEZIER_TYPES if q >= highest)


class BezierMesh:
    """The engine's view of a :class:`~mortar1d3d.nurbs.NurbsSolid` (patches of degree 1 … 4 per direction,
    elements of their common degree p = 2, 3 or 4, module docstring).

    Attributes
    ----------
    solid : SolidMesh
        ``nurbs27``, ``nurbs64`` or ``nurbs125`` elements (patch by patch, each patch's elements with the last parameter
        direction fastest), nodes = Bézier control points, with weights.
    T : scipy.sparse.csr_matrix (n_nodes, n_control)
        Mesh node values from control-point values (module docstring).
    element_patch : (n_elements,) int64
        The patch of every element.
    element_span : (n_elements, 3) int64
        The element's span index per parameter direction within its patch.
    nurbs : NurbsSolid
    """

    def __init__(self, nurbs, tol=1e-10):
        if not isinstance(nurbs, NurbsSolid):
            raise TypeError(f"expected a NurbsSolid, got {type(nurbs).__name__}")
        flat_rows, flat_cols, flat_vals = [], [], []
        control, weights, patch_of, spans = [], [], [], []
        d = bezier_type([patch.degrees for patch in nurbs.patches])
        n = d.n_nodes
        order = tensor_order(d.reference_nodes, d.degree)                 # tensor index of each node
        n_el = 0
        for k, patch in enumerate(nurbs.patches):
            P, w, functions, E = patch.bezier_elements((d.degree,) * 3)
            E = E[:, :, order]                                            # [element, function, node]
            rows = n * (n_el + np.arange(len(P)))[:, None, None] + np.arange(n)[None, None, :]
            flat_rows.append(np.broadcast_to(rows, E.shape).ravel())
            flat_cols.append(np.broadcast_to(nurbs.patch_ids[k][functions][:, :, None], E.shape).ravel())
            flat_vals.append(E.ravel())
            control.append(P[:, order])
            weights.append(w[:, order])
            patch_of.append(np.full(len(P), k, dtype=np.int64))
            spans.append(np.stack(np.unravel_index(np.arange(len(P)), patch.element_shape), axis=1))
            n_el += len(P)
        P = np.concatenate(control)                                       # (n_el, n, 3)
        w = np.concatenate(weights)
        merged, keep = merge_coincident(P.reshape(-1, 3), w.reshape(-1), tol)
        node = merged.reshape(n_el, n)
        points = P.reshape(-1, 3)[keep]
        node_weights = w.reshape(-1)[keep]
        # T: the row of a mesh node from the first element that has it (the others agree to round-off)
        flat_rows, flat_cols, flat_vals = (np.concatenate(a) for a in (flat_rows, flat_cols, flat_vals))
        local_to_node = np.full(n_el * n, -1, dtype=np.int64)
        local_to_node[keep] = np.arange(len(keep))
        take = local_to_node[flat_rows] >= 0
        nonzero = take & (flat_vals != 0.0)
        self.T = sp.csr_matrix((flat_vals[nonzero], (local_to_node[flat_rows[nonzero]], flat_cols[nonzero])),
                               shape=(len(keep), nurbs.n_control))
        if len(nurbs.patches) > 1 and len({patch.degrees for patch in nurbs.patches}) > 1:
            _check_joins(self.T, merged, flat_rows, flat_cols, flat_vals, n, np.concatenate(patch_of))
        self.solid = SolidMesh(points, {d.name: node}, weights=node_weights)
        self.element_patch = np.concatenate(patch_of)
        self.element_span = np.concatenate(spans).astype(np.int64)
        self.nurbs = nurbs

    def control_to_nodes(self, values):
        """Mesh node values (n_nodes, k) from control-point values (n_control, k) (e.g. displacements)."""
        return self.T @ np.asarray(values, dtype=np.float64)

    def nodes_to_control(self, M):
        """An operator on mesh node DOFs (columns 3 a + i, e.g. the mortar M) as one on control-point DOFs."""
        return sp.csr_matrix(M @ sp.kron(self.T, sp.identity(3), format="csr"))

    def __repr__(self):
        return f"BezierMesh({self.solid.n_elements} {self.solid.blocks[0][0].name} elements, {self.solid.n_nodes} nodes, " \
               f"{self.nurbs.n_control} control points)"


def _check_joins(T, merged, rows, cols, vals, n, element_patch):
    """ValueError unless every element's own map of its nodes (COO ``rows`` = element n + node, ``cols``,
    ``vals``) equals the row of ``T`` the node took from the first element that has it. Patches of
    different degrees joined at coincident control points can share Bézier nodes whose values their
    control points give differently (a quadratic face of one against a linear face of the other)."""
    local = sp.csr_matrix((vals, (rows, cols)), shape=(len(merged), T.shape[1]))
    gap = abs(local - T[merged]).max(axis=1).toarray().ravel()
    bad = np.flatnonzero(gap > 1e-10)
    if len(bad):
        other = np.flatnonzero(merged == merged[bad[0]])[0]
        a, b = int(element_patch[other // n]), int(element_patch[bad[0] // n])
        raise ValueError(f"patches[{b}] meets patches[{a}] where their control nets differ (a face of other degrees "
                         "shares Bézier points with it); elevate the patches to one degree (NurbsPatch.elevate) "
                         "before joining them")


def element_values(solid, xi, values):
    """Node fields interpolated at element parameters: ``values`` (n_nodes, k) at the points ``xi`` (q, 3)
    of every element of ``solid``, with the elements' own functions (rational ones with their node
    weights): (n_elements, q, k). All blocks must have the same parameter space (``xi`` is shared)."""
    values = np.asarray(values, dtype=np.float64)
    out = []
    for d, conn in solid.blocks:
        B, dB = polynomial_values(d.code, xi, d.n_nodes)
        if d.rational:
            B = rational_values(B, dB, solid.weights[conn[:, : d.n_nodes]])[0]
        else:
            B = np.broadcast_to(B, (len(conn),) + B.shape)
        out.append(np.einsum("mqa,mak->mqk", B, values[conn[:, : d.n_nodes]]))
    return np.concatenate(out)


def sampled_cells(solid, point_data):
    """A polynomial stand-in of a mesh with rational elements, for output: every rational element of
    degree p becomes (p-1)³ ``hexahedron27`` cells (one for p = 2), each through the element's exact
    points at the hexahedron27 lattice parameters of its sub-box of [-1, 1]³ (the element's nodes are
    control points, mostly off the body), with the node fields interpolated there; polynomial blocks
    keep their nodes. Returns points (n, 3), cells [(meshio type, conn)], point data {name: (n, ...)}."""
    rational = [d.rational for d, _ in solid.blocks]
    keep = not all(rational)                     # polynomial blocks use the original nodes
    points = [solid.points] if keep else []
    data = {k: [np.asarray(v, dtype=np.float64).reshape(solid.n_nodes, -1)] if keep else []
            for k, v in point_data.items()}
    cells, start = [], solid.n_nodes if keep else 0
    for (d, conn), is_rational in zip(solid.blocks, rational):
        if not is_rational:
            cells.append((d.name, conn))
            continue
        if d.family_type.name != "hex":
            raise ValueError(f"output of rational {d.name} elements: only hexahedra are sampled")
        xi = sub_box_points(max(d.degree - 1, 1))
        sub = _single_block(solid, d, conn)
        points.append(element_values(sub, xi, solid.points).reshape(-1, 3))
        for k, v in point_data.items():
            v = np.asarray(v, dtype=np.float64)
            data[k].append(element_values(sub, xi, v.reshape(solid.n_nodes, -1)).reshape(-1, *v.shape[1:]))
        n_cells = len(xi) // 27 * len(conn)
        cells.append(("hexahedron27", start + np.arange(27 * n_cells).reshape(-1, 27)))
        start += 27 * n_cells
    return np.concatenate(points), cells, {k: np.concatenate(v) for k, v in data.items()}


def sub_box_points(s):
    """The hexahedron27 lattice parameters of the s³ sub-boxes of [-1, 1]³ (box by box, the last
    direction fastest): (27 s³, 3); ``s = 1`` gives the hexahedron27 nodes themselves."""
    if s == 1:
        return QUADRATIC_NODES
    h = 2.0 / s
    lower = -1.0 + h * np.stack(np.meshgrid(*(np.arange(s),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    return (lower[:, None, :] + 0.5 * h * (QUADRATIC_NODES[None] + 1.0)).reshape(-1, 3)


class _single_block:
    """One block of a mesh seen as a mesh (``blocks`` and ``weights``) for :func:`element_values`."""

    def __init__(self, solid, d, conn):
        self.blocks, self.weights = [(d, conn)], solid.weights


def bezier_mesh(nurbs, tol=1e-10):
    """The engine's mesh of a :class:`~mortar1d3d.nurbs.NurbsSolid` (degrees 1 … 4 per direction): a :class:`BezierMesh`."""
    return BezierMesh(nurbs, tol)


__all__ = ["BezierMesh", "bezier_mesh", "bezier_type", "common_degree", "element_values", "sampled_cells", "sub_box_points",
           "BEZIER_TYPES"]
