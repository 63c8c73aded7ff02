"""From NURBS patches to the engine: a mesh of rational Bézier elements and the map to control points.

Every quadratic NURBS element becomes a ``nurbs27`` element (:mod:`mortar1d3d.elements.solid.nurbs27`):
its 27 Bézier control points and weights from Bézier extraction, in hexahedron27 order. Bézier
points that coincide (same position and weight: the shared faces, edges and corners of neighbouring
elements, which are the same rational functions there) are one mesh node. The NURBS functions are
combinations of the Bézier ones, R_i = Σ_a E_ia R^b_a, so anything the engine or the model computes
on the Bézier mesh maps to the control points by the sparse matrix ``T`` (n_mesh_nodes, n_control):

    node values = T @ control-point values,   M_control = M_mesh (T ⊗ I₃),   K_control = Tᵀ K_mesh T

(the mesh's nodes are ``T @ control``, so the constraint residual D q_B - M X_S is the same in both).
"""
import numpy as np
import scipy.sparse as sp

from ..elements.solid.hex_family import QUADRATIC_LATTICE
from ..mesh import SolidMesh
from ..physics.rational_surface import polynomial_values, rational_values
from .patch import NurbsSolid, merge_coincident

#: tensor (C-order 3 × 3 × 3) index of each hexahedron27 node
VTK_FROM_TENSOR = (QUADRATIC_LATTICE[:, 0] * 3 + QUADRATIC_LATTICE[:, 1]) * 3 + QUADRATIC_LATTICE[:, 2]


class BezierMesh:
    """The engine's view of a :class:`~mortar1d3d.nurbs.NurbsSolid` (quadratic patches).

    Attributes
    ----------
    solid : SolidMesh
        ``nurbs27`` elements (patch by patch, each patch's elements with the last parameter
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
        for k, patch in enumerate(nurbs.patches):
            if patch.degrees != (2, 2, 2):
                raise ValueError(f"patches[{k}]: the engine takes quadratic NURBS (nurbs27 elements), got degrees "
                                 f"{patch.degrees}")
            P, w, functions, E = patch.bezier_elements()
            ids.append(nurbs.patch_ids[k][functions])                    # (m, 27) global control points
            control.append(P[:, VTK_FROM_TENSOR])
            weights.append(w[:, VTK_FROM_TENSOR])
            vals.append(E[:, :, VTK_FROM_TENSOR])                         # [element, function, vtk node]
            patch_of.append(np.full(len(P), k, dtype=np.int64))
            spans.append(np.stack(np.unravel_index(np.arange(len(P)), patch.element_shape), axis=1))
        P = np.concatenate(control)                                       # (n_el, 27, 3)
        w = np.concatenate(weights)
        n_el = len(P)
        merged, keep = merge_coincident(P.reshape(-1, 3), w.reshape(-1), tol)
        node = merged.reshape(n_el, 27)
        points = P.reshape(-1, 3)[keep]
        node_weights = w.reshape(-1)[keep]
        # T: the row of a mesh node from the first element that has it (the others agree to round-off)
        E = np.concatenate(vals)
        flat_rows = np.broadcast_to(27 * np.arange(n_el)[:, None, None] + np.arange(27)[None, None, :], E.shape).ravel()
        flat_cols = np.broadcast_to(np.concatenate(ids)[:, :, None], E.shape).ravel()
        flat_vals = E.ravel()
        local_to_node = np.full(n_el * 27, -1, dtype=np.int64)
        local_to_node[keep] = np.arange(len(keep))
        take = local_to_node[flat_rows] >= 0
        nonzero = take & (flat_vals != 0.0)
        self.T = sp.csr_matrix((flat_vals[nonzero], (local_to_node[flat_rows[nonzero]], flat_cols[nonzero])),
                               shape=(len(keep), nurbs.n_control))
        self.solid = SolidMesh(points, {"nurbs27": node}, weights=node_weights)
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
        return f"BezierMesh({self.solid.n_elements} nurbs27 elements, {self.solid.n_nodes} nodes, " \
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
    """A polynomial stand-in of a mesh with rational elements, for output: every rational element becomes
    a ``hexahedron27`` cell through its exact points at the hexahedron27 lattice parameters (its
    nodes are control points, mostly off the body), with the node fields interpolated there;
    polynomial blocks keep their nodes. Returns points (n, 3), cells [(meshio type, conn)], point
    data {name: (n, ...)}."""
    from ..elements.solid.hex_family import QUADRATIC_NODES

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
        if d.family_type.name != "hex" or d.n_nodes != 27:
            raise ValueError(f"output of rational {d.name} elements: only triquadratic hexahedra are sampled")
        sub = _single_block(solid, d, conn)
        points.append(element_values(sub, QUADRATIC_NODES, solid.points).reshape(-1, 3))
        for k, v in point_data.items():
            v = np.asarray(v, dtype=np.float64)
            data[k].append(element_values(sub, QUADRATIC_NODES, v.reshape(solid.n_nodes, -1)).reshape(-1, *v.shape[1:]))
        cells.append(("hexahedron27", start + np.arange(27 * len(conn)).reshape(-1, 27)))
        start += 27 * len(conn)
    return np.concatenate(points), cells, {k: np.concatenate(v) for k, v in data.items()}


class _single_block:
    """One block of a mesh seen as a mesh (``blocks`` and ``weights``) for :func:`element_values`."""

    def __init__(self, solid, d, conn):
        self.blocks, self.weights = [(d, conn)], solid.weights


def bezier_mesh(nurbs, tol=1e-10):
    """The engine's mesh of a quadratic :class:`~mortar1d3d.nurbs.NurbsSolid`: a :class:`BezierMesh`."""
    return BezierMesh(nurbs, tol)


__all__ = ["BezierMesh", "bezier_mesh", "element_values", "sampled_cells", "VTK_FROM_TENSOR"]
