"""Surface loads on the boundary of a :class:`~mortar1d3d.mesh.SolidMesh`: dead traction and
follower pressure, for every solid element type (linear and quadratic faces).

A face is named by ``(element, face, code)``: the global element number, the local face index
into the element descriptor's ``faces`` table and the element type code. The descriptor gives
the face as an affine map of the parameter space, ``ξ(u, v) = origin + u a + v b``, of its
family's face shape (``u, v ∈ [-1, 1]`` on a quadrilateral, ``u, v >= 0, u + v <= 1`` on a
triangle), and an outward normal; ``a × b`` is parallel to that normal, with either sign
(``orientation`` below). Every table here is per (type, face): the faces of one element may
differ in shape, node count and rule.

Face functions. The nodes of a face are the element nodes whose reference coordinates lie on it
(e.g. 4/8/9 for hexahedron/hexahedron20/hexahedron27, 3/6 for tetra/tetra10). The volume shape
functions of the other nodes vanish identically on the face, so the face functions are the
volume functions restricted to ``ξ(u, v)``; their tangential derivatives are
``∂N/∂u = ∇_ξ N · a`` and ``∂N/∂v = ∇_ξ N · b``. Both are tabulated once per (type, face,
quadrature point) and only the face nodes are used in the kernels: this keeps the kernels free of
element dispatch and never scatters the round-off values that the vanishing functions take at
points such as ``1 - u - v`` computed in floating point.

Quadrature. Each face uses its shape's rule (:mod:`mortar1d3d.elements.solid.face_shapes`):
quadrilateral faces 3 × 3 Gauss–Legendre points, triangular faces the 6-point degree-4 rule
(Strang–Fix / Dunavant). The follower load ``N (x_,u × x_,v)`` is a polynomial on
the face: on a 9-node face ``N ∈ Q2``, ``x_,u ∈ Q(1,2)``, ``x_,v ∈ Q(2,1)``, so the integrand is
in ``Q(5,5)``, which 3 points per direction integrate exactly; on a 6-node triangle the degrees are
2 + 1 + 1 = 4. Both rules are therefore exact for the follower pressure and its tangent on any
(curved, deformed) face of up to these degrees, and exact for the dead traction on flat faces
(where ``|X_,u × X_,v|`` is constant). Faces of rational (NURBS) elements get per-face tables of
their rational functions and a Gauss rule that is not exact (:mod:`.rational_surface`).

Assembly. The kernels compute each face's local vector/matrix independently (``prange`` over
faces, no shared accumulators); the global vector is summed with ``np.bincount`` and the CSR
matrix through a cached map from local entries to CSR positions, both sequential in the face
order. Results are bit-identical for any number of threads.
"""
from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from .._config import njit
from .._parallel import in_parallel
from ..elements.solid.dispatch import BY_CODE, MAX_FACES, MAX_NODES, deriv, shape
from ..geometry.linalg import norm3
from .rational_surface import kernel_tables

#: dtype of face lists (see :func:`boundary_faces`)
FACE_DTYPE = np.dtype([("element", np.int64), ("face", np.int64), ("code", np.int64)])


def _nodes_on(d, f):
    """Local ids of the nodes of type ``d`` whose reference coordinates lie on the plane of face f."""
    origin, _a, _b, normal = d.faces[f]
    return np.flatnonzero(np.abs((d.reference_nodes - origin) @ normal) < 1e-12)


class _FaceTables:
    """Per element type code and face: face nodes, quadrature and tabulated face functions (padded).

    nodes : (n_codes, MAX_FACES, max_face_nodes) int64, local node ids of each face (-1 padded)
    n_nodes : (n_codes, MAX_FACES) int64, nodes of each face
    n_faces : (n_codes,) int64
    n_points : (n_codes, MAX_FACES) int64, quadrature points of each face (its shape's rule)
    weights : (n_codes, MAX_FACES, max_face_points) float64
    N, dN_du, dN_dv : (n_codes, MAX_FACES, max_face_points, max_face_nodes) float64
    orientation : (n_codes, MAX_FACES) float64, sign of ``(a × b) · outward normal``
    max_corners : int, most corners of any face (width of the keys of :func:`boundary_faces`)
    """

    def __init__(self):
        n_codes = len(BY_CODE)
        max_nodes = max(len(_nodes_on(d, f)) for d in BY_CODE.values() for f in range(d.n_faces))
        shapes = [s for d in BY_CODE.values() for s in d.family_type.face_shapes]
        max_points = max(len(s.rule()[1]) for s in shapes)
        self.max_corners = max(s.n_corners for s in shapes)
        self.nodes = np.full((n_codes, MAX_FACES, max_nodes), -1, dtype=np.int64)
        self.n_nodes = np.zeros((n_codes, MAX_FACES), dtype=np.int64)
        self.n_faces = np.zeros(n_codes, dtype=np.int64)
        self.n_points = np.zeros((n_codes, MAX_FACES), dtype=np.int64)
        self.weights = np.zeros((n_codes, MAX_FACES, max_points))
        shape4 = (n_codes, MAX_FACES, max_points, max_nodes)
        self.N, self.dN_du, self.dN_dv = np.zeros(shape4), np.zeros(shape4), np.zeros(shape4)
        self.orientation = np.zeros((n_codes, MAX_FACES))
        N = np.empty(MAX_NODES)
        dN = np.empty((MAX_NODES, 3))
        for code, d in BY_CODE.items():
            self.n_faces[code] = d.n_faces
            for f in range(d.n_faces):
                origin, a, b, normal = d.faces[f]
                points, weights = d.family_type.face_shapes[f].rule()
                self.n_points[code, f] = len(weights)
                self.weights[code, f, : len(weights)] = weights
                on_face = _nodes_on(d, f)
                m = len(on_face)
                self.n_nodes[code, f] = m
                self.nodes[code, f, :m] = on_face
                self.orientation[code, f] = np.sign(np.cross(a, b) @ normal)
                for q, (u, v) in enumerate(points):
                    xi = origin + u * a + v * b
                    shape(code, xi, N)
                    deriv(code, xi, dN)
                    self.N[code, f, q, :m] = N[on_face]
                    self.dN_du[code, f, q, :m] = dN[on_face] @ a
                    self.dN_dv[code, f, q, :m] = dN[on_face] @ b


@lru_cache(maxsize=None)
def face_tables():
    """The (cached) :class:`_FaceTables`; built on first use, not at import."""
    return _FaceTables()


def face_nodes(code, face):
    """Local node ids (int64) of face ``face`` of element type ``code``: corners and mid-side nodes."""
    tables = face_tables()
    return tables.nodes[code, face, : tables.n_nodes[code, face]].copy()


# --------------------------------------------------------------------------------------------
# boundary faces


def boundary_faces(solid, nodes=None):
    """Faces of ``solid`` that belong to exactly one element.

    Parameters
    ----------
    solid : SolidMesh
    nodes : (k,) int array_like of node ids, or (n_nodes,) bool mask, optional
        Keep only boundary faces all of whose nodes (corners and mid-side nodes) are in this set.

    Returns
    -------
    (n_faces,) structured array of :data:`FACE_DTYPE`
        Fields ``element`` (global element number), ``face`` (local face index into the
        element descriptor's ``faces``) and ``code`` (element type code), sorted by element, then
        face.

    Notes
    -----
    Two faces are the same if they have the same corner nodes: each face's sorted corner ids form
    a key, and keys that occur once are boundary faces. Mid-side nodes do not enter the key (a
    conforming mesh shares them whenever it shares the corners).
    """
    tables = face_tables()
    keys, element, face, code = [], [], [], []
    start = 0
    for d, conn in solid.blocks:
        ids = np.arange(start, start + len(conn), dtype=np.int64)
        for f, corners in enumerate(d.face_nodes):
            key = np.full((len(conn), tables.max_corners), -1, dtype=np.int64)
            key[:, : len(corners)] = np.sort(conn[:, list(corners)], axis=1)
            keys.append(key)
            element.append(ids)
            face.append(np.full(len(conn), f, dtype=np.int64))
            code.append(np.full(len(conn), d.code, dtype=np.int64))
        start += len(conn)
    keys = np.concatenate(keys)
    element, face, code = np.concatenate(element), np.concatenate(face), np.concatenate(code)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    keep = counts[inverse.ravel()] == 1
    if nodes is not None:
        mask = _node_mask(nodes, solid.n_nodes)
        m = tables.n_nodes[code, face]
        for count in np.unique(m[keep]):
            idx = np.flatnonzero(keep & (m == count))
            local = tables.nodes[code[idx], face[idx], :count]
            keep[idx] = mask[solid.connectivity[element[idx, None], local]].all(axis=1)
    order = np.flatnonzero(keep)
    order = order[np.lexsort((face[order], element[order]))]
    out = np.empty(len(order), dtype=FACE_DTYPE)
    out["element"], out["face"], out["code"] = element[order], face[order], code[order]
    return out


def _node_mask(nodes, n_nodes):
    nodes = np.asarray(nodes)
    if nodes.dtype == bool:
        if nodes.shape != (n_nodes,):
            raise ValueError(f"node mask: expected shape ({n_nodes},), got {nodes.shape}")
        return nodes
    if nodes.size and not np.issubdtype(nodes.dtype, np.integer):
        raise ValueError("nodes: expected integer node ids or a boolean mask")
    nodes = nodes.astype(np.int64).ravel()
    if nodes.size and (nodes.min() < 0 or nodes.max() >= n_nodes):
        raise ValueError(f"nodes: ids out of range [0, {n_nodes})")
    mask = np.zeros(n_nodes, dtype=bool)
    mask[nodes] = True
    return mask


class _FaceSet:
    """Validated face list with its DOF map (flat, with offsets)."""

    def __init__(self, solid, faces):
        faces = np.asarray(faces)
        if faces.dtype.names is None or not {"element", "face"} <= set(faces.dtype.names):
            raise TypeError("faces: expected a structured array with fields 'element' and 'face' "
                            "(as returned by boundary_faces)")
        faces = faces.ravel()
        self.element = np.ascontiguousarray(faces["element"], dtype=np.int64)
        self.face = np.ascontiguousarray(faces["face"], dtype=np.int64)
        bad = (self.element < 0) | (self.element >= solid.n_elements)
        if bad.any():
            raise ValueError(f"faces: element numbers out of range [0, {solid.n_elements}) at "
                             f"positions {np.flatnonzero(bad)[:10].tolist()}")
        self.code = np.ascontiguousarray(solid.element_codes[self.element])
        if "code" in faces.dtype.names and (faces["code"] != self.code).any():
            raise ValueError("faces: 'code' does not match the element types of the solid mesh")
        tables = face_tables()
        bad = (self.face < 0) | (self.face >= tables.n_faces[self.code])
        if bad.any():
            raise ValueError(f"faces: local face index out of range at positions "
                             f"{np.flatnonzero(bad)[:10].tolist()}")
        self.n_dofs = 3 * solid.n_nodes
        self.n_face_nodes = tables.n_nodes[self.code, self.face]
        n_local = 3 * self.n_face_nodes          # DOFs per face
        self.f_offsets = np.zeros(len(self.code) + 1, dtype=np.int64)
        np.cumsum(n_local, out=self.f_offsets[1:])
        self.k_offsets = np.zeros(len(self.code) + 1, dtype=np.int64)
        np.cumsum(n_local * n_local, out=self.k_offsets[1:])
        self.dofs = np.empty(self.f_offsets[-1], dtype=np.int64)
        for count in np.unique(self.n_face_nodes):
            idx = np.flatnonzero(self.n_face_nodes == count)
            m = 3 * count
            local = tables.nodes[self.code[idx], self.face[idx], :count]
            nodes = solid.connectivity[self.element[idx, None], local]
            self.dofs[self.f_offsets[idx, None] + np.arange(m)] = (3 * nodes[:, :, None]
                                                                  + np.arange(3)).reshape(len(idx), m)
        self._pattern = None

    def __len__(self):
        return len(self.element)

    def assemble_vector(self, local):
        # bincount sums in input order: deterministic, independent of the thread count
        return np.bincount(self.dofs, weights=local, minlength=self.n_dofs)

    def assemble_matrix(self, local):
        if self._pattern is None:
            self._pattern = self._csr_pattern()
        indptr, indices, position, nnz = self._pattern
        data = np.bincount(position, weights=local, minlength=nnz)
        return sp.csr_matrix((data, indices.copy(), indptr.copy()), shape=(self.n_dofs, self.n_dofs))

    def _csr_pattern(self):
        """CSR structure of the face matrices and the position of every local entry in it.

        Built on node pairs (3 × 3 blocks), nine times fewer keys to sort than DOF pairs.
        """
        n_nodes = self.n_dofs // 3
        n_face_nodes = self.n_face_nodes
        pair_offsets = np.zeros(len(self) + 1, dtype=np.int64)
        np.cumsum(n_face_nodes * n_face_nodes, out=pair_offsets[1:])
        node_rows = np.empty(pair_offsets[-1], dtype=np.int64)
        node_cols = np.empty_like(node_rows)
        groups = []
        for m in np.unique(n_face_nodes):
            idx = np.flatnonzero(n_face_nodes == m)
            nodes = self.dofs[self.f_offsets[idx, None] + 3 * np.arange(m)] // 3       # (k, m)
            at = pair_offsets[idx, None] + np.arange(m * m)
            node_rows[at] = np.repeat(nodes, m, axis=1)
            node_cols[at] = np.tile(nodes, (1, m))
            groups.append((idx, m, at))
        keys, pair = np.unique(node_rows * n_nodes + node_cols, return_inverse=True)
        pair = pair.ravel()
        key_row = keys // n_nodes
        count = np.bincount(key_row, minlength=n_nodes)           # blocks per node row
        start = np.zeros(n_nodes + 1, dtype=np.int64)
        np.cumsum(count, out=start[1:])
        rank = np.arange(len(keys)) - start[key_row]               # block's place in its row
        # DOF row 3a+i holds the 3 count[a] columns 3b+j of its blocks, b ascending
        indptr = np.zeros(self.n_dofs + 1, dtype=np.int64)
        np.cumsum(np.repeat(3 * count, 3), out=indptr[1:])
        indices = np.empty(indptr[-1], dtype=np.int64)
        for i in range(3):
            for j in range(3):
                indices[indptr[3 * key_row + i] + 3 * rank + j] = 3 * (keys % n_nodes) + j
        position = np.empty(self.k_offsets[-1], dtype=np.int64)
        ij = np.arange(3)
        for idx, m, at in groups:
            u = pair[at].reshape(len(idx), m, 1, m, 1)              # unique block of (k, l)
            row = key_row[u]
            pos = (indptr[3 * row + ij[None, None, :, None, None]] + 3 * rank[u] + ij[None, None, None, None, :])
            local = self.k_offsets[idx, None] + np.arange(9 * m * m)    # (3k+i) 3m + 3l + j, row-major
            position[local] = pos.reshape(len(idx), 9 * m * m)
        return indptr, indices, position, len(indices)


def _as_field(u, n_nodes, what):
    u = np.asarray(u, dtype=np.float64)
    if u.shape == (3 * n_nodes,):
        u = u.reshape(n_nodes, 3)
    if u.shape != (n_nodes, 3):
        raise ValueError(f"{what}: expected shape ({n_nodes}, 3) or ({3 * n_nodes},), got {u.shape}")
    return u


# --------------------------------------------------------------------------------------------
# kernels


@njit
def _face_tangents(x, conn, e, c, fc, q, m, nodes, dN_du, dN_dv):
    """``x_,u`` and ``x_,v`` (six scalars) of face ``fc`` of element ``e`` (type ``c``) at point ``q``.

    ``x`` are the node positions, reference (dead traction) or current (follower pressure).
    """
    xu0 = xu1 = xu2 = xv0 = xv1 = xv2 = 0.0
    for k in range(m):
        a = conn[e, nodes[c, fc, k]]
        du, dv = dN_du[c, fc, q, k], dN_dv[c, fc, q, k]
        xu0 += du * x[a, 0]
        xu1 += du * x[a, 1]
        xu2 += du * x[a, 2]
        xv0 += dv * x[a, 0]
        xv1 += dv * x[a, 1]
        xv2 += dv * x[a, 2]
    return xu0, xu1, xu2, xv0, xv1, xv2


@njit
def _traction_kernel(X, conn, element, code, face, t, nodes, n_face_nodes, n_points, weights, N, dN_du,
                     dN_dv, f_offsets, f_local):
    """Local nodal forces ``∫ N_k t dA0`` of every face into ``f_local`` (flat, ``f_offsets``)."""
    _traction_kernel_workers(element.shape[0], X, conn, element, code, face, t, nodes, n_face_nodes, n_points,
                             weights, N, dN_du, dN_dv, f_offsets, f_local)


@njit
def _traction_kernel_worker(i, X, conn, element, code, face, t, nodes, n_face_nodes, n_points, weights, N, dN_du,
                            dN_dv, f_offsets, f_local):
    e, c, fc = element[i], code[i], face[i]
    m = n_face_nodes[c, fc]
    o = f_offsets[i]
    for r in range(3 * m):
        f_local[o + r] = 0.0
    for q in range(n_points[c, fc]):
        xu0, xu1, xu2, xv0, xv1, xv2 = _face_tangents(X, conn, e, c, fc, q, m, nodes, dN_du, dN_dv)
        dA = weights[c, fc, q] * norm3(xu1 * xv2 - xu2 * xv1, xu2 * xv0 - xu0 * xv2, xu0 * xv1 - xu1 * xv0)
        for k in range(m):
            g = dA * N[c, fc, q, k]
            f_local[o + 3 * k] += g * t[i, 0]
            f_local[o + 3 * k + 1] += g * t[i, 1]
            f_local[o + 3 * k + 2] += g * t[i, 2]


_traction_kernel_workers = in_parallel(_traction_kernel_worker)


@njit
def _pressure_kernel(x, conn, element, code, face, p, nodes, n_face_nodes, n_points, weights, N, dN_du, dN_dv,
                     orientation, f_offsets, k_offsets, tangent, f_local, k_local):
    """Local follower forces and, if ``tangent``, their derivatives, face by face.

    ``f_k = -p s Σ_q w_q N_k (x_,u × x_,v)`` and ``∂f_k/∂x_l = -p s Σ_q w_q N_k [c_l]_×`` with
    ``c_l = N_l,v x_,u - N_l,u x_,v`` and ``[c]_× δ = c × δ``; ``s`` orients ``a × b`` outward.
    Local DOF ``3 k + i`` (face node k, component i); the local matrix is row-major.
    """
    _pressure_kernel_workers(element.shape[0], x, conn, element, code, face, p, nodes, n_face_nodes, n_points,
                             weights, N, dN_du, dN_dv, orientation, f_offsets, k_offsets, tangent, f_local, k_local)


@njit
def _pressure_kernel_worker(i, x, conn, element, code, face, p, nodes, n_face_nodes, n_points, weights, N, dN_du,
                            dN_dv, orientation, f_offsets, k_offsets, tangent, f_local, k_local):
    e, c, fc = element[i], code[i], face[i]
    m = n_face_nodes[c, fc]
    nl = 3 * m
    fo = f_offsets[i]
    ko = k_offsets[i]
    for r in range(nl):
        f_local[fo + r] = 0.0
    if tangent:
        for r in range(nl * nl):
            k_local[ko + r] = 0.0
    scale = -p * orientation[c, fc]
    for q in range(n_points[c, fc]):
        xu0, xu1, xu2, xv0, xv1, xv2 = _face_tangents(x, conn, e, c, fc, q, m, nodes, dN_du, dN_dv)
        n0 = xu1 * xv2 - xu2 * xv1
        n1 = xu2 * xv0 - xu0 * xv2
        n2 = xu0 * xv1 - xu1 * xv0
        sw = scale * weights[c, fc, q]
        for k in range(m):
            g = sw * N[c, fc, q, k]
            f_local[fo + 3 * k] += g * n0
            f_local[fo + 3 * k + 1] += g * n1
            f_local[fo + 3 * k + 2] += g * n2
            if tangent:
                for l in range(m):
                    du, dv = dN_du[c, fc, q, l], dN_dv[c, fc, q, l]
                    c0 = g * (dv * xu0 - du * xv0)
                    c1 = g * (dv * xu1 - du * xv1)
                    c2 = g * (dv * xu2 - du * xv2)
                    b = ko + 3 * k * nl + 3 * l
                    k_local[b + 1] -= c2
                    k_local[b + 2] += c1
                    k_local[b + nl] += c2
                    k_local[b + nl + 2] -= c0
                    k_local[b + 2 * nl] -= c1
                    k_local[b + 2 * nl + 1] += c0


_pressure_kernel_workers = in_parallel(_pressure_kernel_worker)


# --------------------------------------------------------------------------------------------
# public API


def traction_force(solid, faces, t):
    """Nodal forces of a dead traction on the reference surface.

    Parameters
    ----------
    solid : SolidMesh
    faces : structured array of :data:`FACE_DTYPE` (from :func:`boundary_faces`)
    t : (3,) or (n_faces, 3) array_like of float
        Traction per unit *reference* area (one vector for all faces, or one per face).

    Returns
    -------
    (3 n_nodes,) float64
        External force vector (node-major DOFs ``3 node + i``); residual = f_int − λ f_ext.

    Notes
    -----
    ``f_a = ∫_{Γ0} N_a t dA0 = Σ_faces Σ_q w_q N_a(u_q, v_q) |X_,u × X_,v| t``. The load does not
    depend on the displacement (no stiffness).
    """
    fs = _FaceSet(solid, faces)
    t = np.asarray(t, dtype=np.float64)
    if t.shape == (3,):
        t = np.broadcast_to(t, (len(fs), 3))
    if t.shape != (len(fs), 3) or not np.isfinite(t).all():
        raise ValueError(f"traction: expected finite values of shape (3,) or ({len(fs)}, 3), got {t.shape}")
    if len(fs) == 0:
        return np.zeros(fs.n_dofs)
    code, face, tables = kernel_tables(solid, fs.code, fs.face, fs.element, face_tables())
    local = np.empty(fs.f_offsets[-1])
    _traction_kernel(solid.points, solid.connectivity, fs.element, code, face, np.ascontiguousarray(t),
                     tables.nodes, tables.n_nodes, tables.n_points, tables.weights, tables.N, tables.dN_du,
                     tables.dN_dv, fs.f_offsets, local)
    return fs.assemble_vector(local)


class Pressure:
    """Follower pressure on faces of a solid: acts along the current normal of the current surface.

    Parameters
    ----------
    solid : SolidMesh
    faces : structured array of :data:`FACE_DTYPE` (from :func:`boundary_faces`)
    p : float
        Pressure (force per current area). Positive ``p`` pushes against the outward normal,
        i.e. into the body, like a gas pressure acting from outside.
    rational_points : int, optional
        Gauss points per direction on faces of rational (NURBS) elements; default: the rule of the
        face's degree (:func:`~mortar1d3d.physics.rational_surface.rational_face_points`, 4 on
        quadratic, 6 on cubic and 7 on quartic faces). Polynomial faces use their exact rule.

    Attributes
    ----------
    p : float
    faces : structured array of :data:`FACE_DTYPE`
    n_tangents : int
        How many times the load stiffness has been assembled (``evaluate(u, tangent=True)``).

    Notes
    -----
    With ``x = X + u`` and ``n da = s (x_,u × x_,v) du dv`` (``s = ±1`` makes the normal point out
    of the element, as the descriptor's outward normal does):

        f_a = -p ∫_Γ N_a n da = -p s Σ_faces Σ_q w_q N_a (x_,u × x_,v)

    ``f`` is an *external* force: the residual is ``f_int − λ f``, so the load contributes
    ``−λ K`` to the residual's tangent, ``K = ∂f/∂u``:

        ∂f_a/∂u_b = -p s Σ_q w_q N_a [N_b,v x_,u − N_b,u x_,v]_×,    [c]_× δ = c × δ.

    ``K`` is not symmetric face by face; it is symmetric overall only for closed surfaces (or
    surfaces whose boundary nodes are fixed), and is never symmetrised here. The quadrature
    integrates both exactly (module docstring).
    """

    def __init__(self, solid, faces, p, rational_points=None):
        self.solid = solid
        self._faces = _FaceSet(solid, faces)
        self.faces = np.empty(len(self._faces), dtype=FACE_DTYPE)
        self.faces["element"], self.faces["face"], self.faces["code"] = (
            self._faces.element, self._faces.face, self._faces.code)
        p = float(p)
        if not np.isfinite(p):
            raise ValueError(f"pressure must be finite, got {p}")
        self.p = p
        self.n_tangents = 0
        # rational (NURBS) faces get per-face tables; polynomial ones index the type tables
        self._kernel_tables = kernel_tables(solid, self._faces.code, self._faces.face, self._faces.element,
                                            face_tables(), rational_points)

    def evaluate(self, u=None, tangent=True):
        """Force (and load stiffness) at displacement ``u``.

        Parameters
        ----------
        u : (n_nodes, 3) or (3 n_nodes,) array_like of float, optional
            Solid displacement; zero if omitted.
        tangent : bool
            Also assemble ``K = ∂f/∂u``.

        Returns
        -------
        f : (3 n_nodes,) float64
            External force.
        K : scipy.sparse.csr_matrix (3 n_nodes, 3 n_nodes), or None if ``tangent`` is False
        """
        solid, fs = self.solid, self._faces
        x = solid.points if u is None else solid.points + _as_field(u, solid.n_nodes, "displacement")
        if not np.isfinite(x).all():
            raise ValueError("displacement: NaN or infinite values")
        tangent = bool(tangent)
        code, face, tables = self._kernel_tables
        f_local = np.empty(fs.f_offsets[-1])
        k_local = np.empty(fs.k_offsets[-1] if tangent else 0)
        if len(fs):
            _pressure_kernel(np.ascontiguousarray(x), solid.connectivity, fs.element, code, face, self.p,
                             tables.nodes, tables.n_nodes, tables.n_points, tables.weights, tables.N,
                             tables.dN_du, tables.dN_dv, tables.orientation, fs.f_offsets, fs.k_offsets,
                             tangent, f_local, k_local)
        f = fs.assemble_vector(f_local)
        if not tangent:
            return f, None
        self.n_tangents += 1
        return f, fs.assemble_matrix(k_local)

    def __repr__(self):
        return f"Pressure(p={self.p!r}, {len(self.faces)} faces)"
