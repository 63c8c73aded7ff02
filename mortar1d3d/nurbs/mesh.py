"""From NURBS patches to the engine: a mesh of rational Bézier elements and the map to control points.

Every NURBS element of degree p in all three directions becomes the rational Bézier element type of
that degree (``nurbs27`` for p = 2, ``nurbs64`` for p = 3: :mod:`mortar1d3d.elements.solid.bezier_hex`):
its (p+1)³ Bézier control points and weights from Bézier extraction, in the type's node order. Bézier
points that coincide (same position and weight: the shared faces, edges and corners of neighbouring
elements, which are the same rational functions there) are one mesh node. The NURBS functions are
combinations of the Bézier ones, R_i = Σ_a E_ia R^b_a, so anything the engine or the model computes
on the Bézier mesh maps to the control points by the sparse matrix ``T`` (n_mesh_nodes, n_control):

    node values = T @ control-point values,   M_control = M_mesh (T ⊗ I₃),   K_control = Tᵀ K_mesh T

(the mesh's nodes are ``T @ control``, so the constraint residual D q_B - M X_S is the same in both).
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


def bezier_type(degrees, what="patch"):
    """The rational Bézier element type of a patch of ``degrees`` (three equal degrees with a registered
    type); ValueError naming ``what`` otherwise."""
    p = degrees[0]
    if len(set(degrees)) != 1 or p not in BEZIER_TYPES:
        raise ValueError(f"{what}: the engine takes NURBS of equal degree in the three directions, one of "
                         f"{sorted(BEZIER_TYPES)} (element types {', '.join(d.name for d in BEZIER_TYPES.values())}); "
                         f"got degrees {tuple(degrees)}")
    return BEZIER_TYPES[p]


class BezierMesh:
    """The engine's view of a :class:`~mortar1d3d.nurbs.NurbsSolid` (patches of one degree p = 2 or 3).

    Attributes
    ----------
    solid : SolidMesh
        ``nurbs27`` or ``nurbs64`` elements (patch by patch, each patch's elements with the last parameter
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
        ids, vals = [], []
        control, weights, patch_of, spans = [], [], [], []
        d = bezier_type(nurbs.patches[0].degrees, "patches[0]")
        n = d.n_nodes
        order = tensor_order(d.reference_nodes, d.degree)                 # tensor index of each node
        for k, patch in enumerate(nurbs.patches):
            if patch.degrees != nurbs.patches[0].degrees:
                raise ValueError(f"patches[{k}]: degrees {patch.degrees}, patches[0] has {nurbs.patches[0].degrees}; "
                                 f"all patches of a solid must have the same degrees")
            P, w, functions, E = patch.bezier_elements()
            ids.append(nurbs.patch_ids[k][functions])                    # (m, n) global control points
            control.append(P[:, order])
            weights.append(w[:, order])
            vals.append(E[:, :, order])                                   # [element, function, node]
            patch_of.append(np.full(len(P), k, dtype=np.int64))
            spans.append(np.stack(np.unravel_index(np.arange(len(P)), patch.element_shape), axis=1))
        P = np.concatenate(control)                                       # (n_el, n, 3)
        w = np.concatenate(weights)
        n_el = len(P)
        merged, keep = merge_coincident(P.reshape(-1, 3), w.reshape(-1), tol)
        node = merged.reshape(n_el, n)
        points = P.reshape(-1, 3)[keep]
        node_weights = w.reshape(-1)[keep]
        # T: the row of a mesh node from the first element that has it (the others agree to round-off)
        E = np.concatenate(vals)
        flat_rows = np.broadcast_to(n * np.arange(n_el)[:, None, None] + np.arange(n)[None, None, :], E.shape).ravel()
        flat_cols = np.broadcast_to(np.concatenate(ids)[:, :, None], E.shape).ravel()
        flat_vals = E.ravel()
        local_to_node = np.full(n_el * n, -1, dtype=np.int64)
        local_to_node[keep] = np.arange(len(keep))
        take = local_to_node[flat_rows] >= 0
        nonzero = take & (flat_vals != 0.0)
        self.T = sp.csr_matrix((flat_vals[nonzero], (local_to_node[flat_rows[nonzero]], flat_cols[nonzero])),
                               shape=(len(keep), nurbs.n_control))
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
    """The engine's mesh of a quadratic or cubic :class:`~mortar1d3d.nurbs.NurbsSolid`: a :class:`BezierMesh`."""
    return BezierMesh(nurbs, tol)


__all__ = ["BezierMesh", "bezier_mesh", "bezier_type", "element_values", "sampled_cells", "sub_box_points",
           "BEZIER_TYPES"]
