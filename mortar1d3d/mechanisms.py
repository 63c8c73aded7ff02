"""Zero-energy modes of beams at the reference state: mechanisms the support check must catch.

A scene can be held against every rigid-body motion and still have a singular tangent: a
truss part outside the solid swings sideways at no cost, a truss chain between two supports
has sideways free interior nodes, a fibre that the coupling ties at a single point can turn
about it. No solver can determine such a motion; :func:`find_mechanisms` finds them before
any solve.

Where the solid is held against rigid motion, a zero-energy mode of the coupled system moves
beams only: the solid's own energy is positive for any motion of a supported solid, so the
solid part of such a mode is zero, and with the solid at rest the coupling energy is zero
exactly when the coupling rows of the beam (``D`` restricted to the coupled LM nodes, or the
beam part of the Gauss-point rows) vanish. The same holds with Lagrange multipliers (the
constraint ``D d_B = M d_S`` with ``d_S = 0``). So each connected chain of beam elements is
probed on its own, with the solid held.

At the stress-free reference state the stiffness of every beam element vanishes exactly on
its rigid motions (translations, rotations; tangents turn with the element), and on nothing
else: a truss bar's ``EA/L (d·(u2 − u1))²``, and for the straight torsion-free element the
three axial and four bending strain modes of the cubic (``tests/test_mechanisms.py`` checks
this against the elements' tangents). A zero-energy mode of a chain is therefore a motion
``w`` with

* ``Π_e w_e = 0`` for every element (``Π_e = I − U_e U_eᵀ``, ``U_e`` an orthonormal basis of
  the element's rigid motions),
* ``C w = 0`` for the chain's coupling rows, and
* ``w = 0`` at Dirichlet DOFs,

i.e. a null vector of ``A = [Π_e P_e (every element); C]`` on the free DOFs. DOFs are made
dimensionless first (positions divided by the adjacent elements' mean length, tangents as
they are) and every coupling row is scaled to unit length, so the singular values of ``A``
compare geometry, not units, section stiffnesses or the penalty. The smallest singular value
of each chain is found by inverse iteration with one banded Cholesky factorisation of
``AᵀA + δI`` for all chains of a beam group at once (block diagonal: every chain iterates on
its own), and measured as ``‖A w‖ / ‖w‖`` directly (not through ``AᵀA``, whose round-off is
the square root of machine precision), an upper bound of the smallest singular value and
exact for the vector it returns. A chain is a mechanism when it is below
:data:`MECHANISM_TOLERANCE`. A legitimately soft chain, e.g. a torsion-free part of ``n``
elements outside the solid, has ``σ ~ 1/n²`` (measured 1.6e-5 for ``n`` ≈ 350): it would need
more than ten thousand elements to be taken for a mechanism; round-off leaves ``σ`` of true
mechanisms near 1e-16.

The argument needs the solid held by its own supports. Where only beams hold it, a motion
that turns the solid rigidly with the beams is the rigid-body check's to find, and one that
turns it through a beam's mechanism shows as that beam's mechanism here.
"""
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, reverse_cuthill_mckee

from ._config import njit

#: smallest singular value of the dimensionless probe operator below which a chain can move freely
MECHANISM_TOLERANCE = 1e-8
#: shift of the Gram matrix relative to its largest diagonal entry (keeps the Cholesky factor of a
#: singular ``AᵀA`` finite; only the speed of the inverse iteration depends on it)
_SHIFT = 1e-12
_ITERATIONS = 3
#: a band wider than this (DOFs) is reordered (reverse Cuthill–McKee) before the banded factorisation
_NATURAL_BAND = 64


@dataclass
class Mechanism:
    """One zero-energy mode of a chain of beam elements.

    Attributes
    ----------
    chain : int
        Index of the chain among the chains of its beam group (connected components).
    nodes : ndarray of int
        Group node ids of the chain.
    sigma : float
        ``‖A w‖ / ‖w‖`` of the mode (dimensionless; see the module docstring).
    mode : ndarray of float
        The mode in the group's centreline DOFs (physical units, largest entry 1).
    moving : ndarray of int
        Group node ids that move in the mode, largest motion first (at least 10 % of the largest).
    """

    chain: int
    nodes: np.ndarray
    sigma: float
    mode: np.ndarray
    moving: np.ndarray


def chains(mesh):
    """(n_chains, label per node) of a beam mesh: its connected components of elements."""
    n = mesh.n_nodes
    e = mesh.elements
    rows = np.repeat(e[:, 0], e.shape[1] - 1)
    cols = e[:, 1:].ravel()
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return connected_components(graph, directed=False)


def _node_scale(mesh):
    """Mean length of the elements at each node (the unit of its position DOFs)."""
    nodes = mesh.elements.ravel()
    lengths = np.repeat(mesh.lengths, mesh.elements.shape[1])
    total = np.bincount(nodes, weights=lengths, minlength=mesh.n_nodes)
    count = np.bincount(nodes, minlength=mesh.n_nodes)
    return np.divide(total, count, out=np.ones(mesh.n_nodes), where=count > 0)


def _dof_layout(mesh, rotation_nodes=None):
    """Per unknown of the probe: its node and whether it is a tangent (or rotation) component.

    With ``rotation_nodes`` the rotation unknowns follow the centreline DOFs; a rotation node
    that is not a mesh node (an element's middle node) counts as its element's first node.
    """
    per_node = mesh.element_type.dofs_per_node // 3          # vectors per node: [r] or [r, t]
    triplet = np.arange(per_node * mesh.n_nodes)
    node, tangent = triplet // per_node, triplet % per_node > 0
    if rotation_nodes is not None:
        owner = np.empty(int(rotation_nodes.max()) + 1, dtype=np.int64)
        owner[rotation_nodes.ravel()] = np.where(rotation_nodes < mesh.n_nodes, rotation_nodes,
                                                 mesh.elements[:, :1]).ravel()
        node = np.concatenate([node, owner])
        tangent = np.concatenate([tangent, np.ones(len(owner), dtype=bool)])
    return np.repeat(node, 3), np.repeat(tangent, 3)


def _framed_element_projectors(mesh, scale, rotation_nodes):
    """``Π_e = I − U_e U_eᵀ`` of elements with a material frame (centreline and rotation nodes).

    The rigid motions of such an element are six, also when it is curved: a translation moves
    its positions; a rotation ω turns positions about the element's midpoint, its tangents
    (``ω × t``) and its triads (spin ``ω``), so the turn about the chord of a straight element
    moves the triads and is no longer invisible.

    Returns
    -------
    dofs : (n_el, 3 (n_f + k)) int64
        Centreline DOFs, then ``n_centreline_dofs + 3 * rotation node + i``.
    projectors : (n_el, nd, nd) float64
    """
    cols = mesh.function_columns()
    cols = cols[:, cols[0] >= 0]                           # Hermite: [r1, t1, r2, t2]
    n_el, n_f = cols.shape
    n_cl = mesh.n_centreline_dofs
    k = rotation_nodes.shape[1]
    dofs = np.concatenate([(3 * cols[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_f),
                           (n_cl + 3 * rotation_nodes[:, :, None] + np.arange(3)).reshape(n_el, 3 * k)], axis=1)
    vectors = np.empty((2 * mesh.n_nodes, 3))
    vectors[0::2], vectors[1::2] = mesh.positions, mesh.tangents
    unit = np.zeros(2 * mesh.n_nodes)
    unit[0::2] = scale
    centre = 0.5 * (mesh.positions[mesh.elements[:, 0]] + mesh.positions[mesh.elements[:, 1]])
    U = np.zeros((n_el, n_f + k, 3, 6))
    v, u = vectors[cols], unit[cols]                       # (n_el, n_f, 3), (n_el, n_f)
    position = u > 0.0
    lever = np.where(position[..., None], (v - centre[:, None, :]) / np.where(position, u, 1.0)[..., None], v)
    for i in range(3):
        w = np.zeros(3)
        w[i] = 1.0
        U[:, :n_f, :, 3 + i] = np.cross(w, lever)
        U[:, :n_f, i, i] = np.where(position, 1.0 / np.where(position, u, 1.0), 0.0)
        U[:, n_f:, i, 3 + i] = 1.0
    U = U.reshape(n_el, 3 * (n_f + k), 6)
    Q, _ = np.linalg.qr(U)
    projectors = np.eye(U.shape[1])[None] - np.einsum("eik,ejk->eij", Q, Q)
    return dofs, projectors


def _element_projectors(mesh, scale):
    """``Π_e = I − U_e U_eᵀ`` on each element's DOFs (dimensionless), and those DOFs.

    Every element here is straight (a truss bar; the torsion-free beam refuses curved ones),
    so its rigid motions are the three translations and the rotations about two axes normal
    to its chord; the spin about the chord moves no DOF (positions on it, tangents along it).

    Returns
    -------
    dofs : (n_el, nd) int64
    projectors : (n_el, nd, nd) float64
    """
    cols = mesh.function_columns()
    cols = np.ascontiguousarray(cols[:, cols[0] >= 0])     # line: 2 columns, Hermite: [r1, t1, r2, t2]
    n_el, n_f = cols.shape
    dofs = (3 * cols[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_f)
    # per DOF triplet: the vector a rigid motion acts on, and the length its positions are measured in
    if mesh.element_type.has_tangents:
        vectors = np.empty((2 * mesh.n_nodes, 3))
        vectors[0::2], vectors[1::2] = mesh.positions, mesh.tangents
        unit = np.zeros(2 * mesh.n_nodes)                  # 0 marks a tangent triplet
        unit[0::2] = scale
    else:
        vectors, unit = mesh.positions, scale
    projectors = np.empty((n_el, 3 * n_f, 3 * n_f))
    _complement_projectors(cols, np.ascontiguousarray(vectors), np.ascontiguousarray(unit, dtype=np.float64),
                           np.ascontiguousarray(mesh.positions[mesh.elements[:, 0]]),
                           np.ascontiguousarray(mesh.positions[mesh.elements[:, 1]]), projectors)
    return dofs, projectors


@njit
def _complement_projectors(cols, vectors, unit, a, b, out):
    """``out[e] = I − U Uᵀ``, U an orthonormal basis (modified Gram–Schmidt) of element e's rigid motions.

    A rigid motion ``t + ω × (x − c)`` (c: the element's midpoint) moves a position triplet by it
    divided by the triplet's length ``unit`` and turns a tangent triplet (``unit`` 0) by ``ω × t``;
    the columns are the three translations and the rotations about two axes normal to the chord.
    """
    n_el, n_f = cols.shape
    nd = 3 * n_f
    U = np.empty((nd, 5))
    axis = np.empty((2, 3))
    lever = np.empty(3)
    d = np.empty(3)
    for e in range(n_el):
        for i in range(3):
            d[i] = b[e, i] - a[e, i]
        norm = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        for i in range(3):
            d[i] /= norm
        # n1 = d × e_x (or d × e_y when d is close to e_x), n2 = d × n1
        if abs(d[0]) < 0.9:
            axis[0, 0], axis[0, 1], axis[0, 2] = 0.0, d[2], -d[1]
        else:
            axis[0, 0], axis[0, 1], axis[0, 2] = -d[2], 0.0, d[0]
        norm = np.sqrt(axis[0, 0] ** 2 + axis[0, 1] ** 2 + axis[0, 2] ** 2)
        for i in range(3):
            axis[0, i] /= norm
        axis[1, 0] = d[1] * axis[0, 2] - d[2] * axis[0, 1]
        axis[1, 1] = d[2] * axis[0, 0] - d[0] * axis[0, 2]
        axis[1, 2] = d[0] * axis[0, 1] - d[1] * axis[0, 0]
        for f in range(n_f):
            c = cols[e, f]
            for i in range(3):
                lever[i] = vectors[c, i] if unit[c] == 0.0 else (vectors[c, i] - 0.5 * (a[e, i] + b[e, i])) / unit[c]
            for i in range(3):
                for k in range(3):
                    U[3 * f + i, k] = (1.0 / unit[c] if (i == k and unit[c] != 0.0) else 0.0)
            for k in range(2):
                w = axis[k]
                U[3 * f + 0, 3 + k] = w[1] * lever[2] - w[2] * lever[1]
                U[3 * f + 1, 3 + k] = w[2] * lever[0] - w[0] * lever[2]
                U[3 * f + 2, 3 + k] = w[0] * lever[1] - w[1] * lever[0]
        for k in range(5):
            for j in range(k):
                dot = 0.0
                for i in range(nd):
                    dot += U[i, j] * U[i, k]
                for i in range(nd):
                    U[i, k] -= dot * U[i, j]
            norm = 0.0
            for i in range(nd):
                norm += U[i, k] * U[i, k]
            norm = np.sqrt(norm)
            for i in range(nd):
                U[i, k] /= norm
        for i in range(nd):
            for j in range(nd):
                v = 1.0 if i == j else 0.0
                for k in range(5):
                    v -= U[i, k] * U[j, k]
                out[e, i, j] = v


@njit
def _unit_rows(indptr, indices, data, scale_inverse, out):
    """Coupling rows in dimensionless DOFs (``C S⁻¹``), each scaled to unit length (zero rows stay zero)."""
    for r in range(len(indptr) - 1):
        norm = 0.0
        for k in range(indptr[r], indptr[r + 1]):
            out[k] = data[k] * scale_inverse[indices[k]]
            norm += out[k] * out[k]
        if norm > 0.0:
            norm = np.sqrt(norm)
            for k in range(indptr[r], indptr[r + 1]):
                out[k] /= norm


@njit
def _add_row_blocks(indptr, indices, data, position, ab):
    """Add ``cᵀc`` of every CSR row c into lower banded storage (``ab[r - q, q]``, r >= q)."""
    for row in range(len(indptr) - 1):
        for a in range(indptr[row], indptr[row + 1]):
            r = position[indices[a]]
            for b in range(indptr[row], indptr[row + 1]):
                q = position[indices[b]]
                if r >= q:
                    ab[r - q, q] += data[a] * data[b]


def _row_band(C, position):
    if C is None or C.nnz == 0:
        return 0
    p = position[C.indices]
    starts = C.indptr[:-1][np.diff(C.indptr) > 0]
    return int((np.maximum.reduceat(p, starts) - np.minimum.reduceat(p, starts)).max())


def find_mechanisms(mesh, coupling_rows=None, fixed=None, tolerance=MECHANISM_TOLERANCE, seed=0,
                    rotation_nodes=None):
    """Zero-energy modes of the chains of one beam mesh at its reference state, solid held.

    Parameters
    ----------
    mesh : BeamMesh
        ``hermite`` (torsion-free beams, 6 DOFs per node) or ``line`` (trusses, 3 per node).
    coupling_rows : sparse matrix (m, n_centreline_dofs), optional
        Rows whose vanishing is what the coupling asks of the beams with the solid at rest:
        ``D`` on the coupled LM rows (mortar, penalty or Lagrange multipliers) or the beam part
        of the Gauss-point rows. Their scale does not matter. None: the beams are not coupled.
    fixed : (n_centreline_dofs,) bool, optional
        Dirichlet DOFs.
    tolerance : float
        See :data:`MECHANISM_TOLERANCE`.
    seed : int
        Start vectors of the inverse iteration (deterministic).
    rotation_nodes : (n_elements, k) int array, optional
        Rotation nodes of each element of a beam with a material frame
        (:meth:`~mortar1d3d.physics.beam_types.BeamType.rotation_nodes`): the probe's unknowns
        are then the centreline DOFs followed by three spins per rotation node (``fixed`` and the
        returned modes have that length; ``coupling_rows`` still act on the centreline only).

    Returns
    -------
    list of Mechanism
        One per chain that can move at no cost (its smallest mode), in chain order.
    """
    n = mesh.n_centreline_dofs
    framed = rotation_nodes is not None and np.size(rotation_nodes) > 0
    if framed:
        rotation_nodes = np.asarray(rotation_nodes, dtype=np.int64)
        n += 3 * (int(rotation_nodes.max()) + 1)
    fixed = np.zeros(n, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    n_chains, label = chains(mesh)
    dof_node, dof_tangent = _dof_layout(mesh, rotation_nodes if framed else None)
    node_scale = _node_scale(mesh)
    scale_inverse = np.where(dof_tangent, 1.0, node_scale[dof_node])      # v = scale_inverse * w
    if framed:
        dofs, Pi = _framed_element_projectors(mesh, node_scale, rotation_nodes)
    else:
        dofs, Pi = _element_projectors(mesh, node_scale)
    C = None
    if coupling_rows is not None and coupling_rows.shape[0]:
        C = sp.csr_matrix(coupling_rows)
        if C.shape[1] < n:          # rotations: the coupling does not act on them
            C = sp.hstack([C, sp.csr_matrix((C.shape[0], n - C.shape[1]))], format="csr")
        C.sum_duplicates()
        data = np.empty(len(C.data))
        _unit_rows(C.indptr, C.indices, C.data, scale_inverse, data)
        C = sp.csr_matrix((data, C.indices, C.indptr), shape=C.shape)
    fixed_dofs = np.flatnonzero(fixed)
    # banded Cholesky of the Gram matrix: chains numbered along their length (every generator and
    # curve spec does that) give a narrow band; otherwise reverse Cuthill–McKee first
    position = np.arange(n)
    order = position
    band = max(_element_band(dofs, position), _row_band(C, position))
    if band > _NATURAL_BAND:
        nd = dofs.shape[1]
        pattern = sp.csr_matrix((np.ones(dofs.size * nd), (np.repeat(dofs, nd, axis=1).ravel(),
                                                           np.tile(dofs, (1, nd)).ravel())), shape=(n, n))
        if C is not None:
            pattern = pattern + (abs(C).T @ abs(C)).tocsr()
        order = reverse_cuthill_mckee(pattern.tocsr(), symmetric_mode=True)
        position = np.empty(n, dtype=np.int64)
        position[order] = np.arange(n)
        band = max(_element_band(dofs, position), _row_band(C, position))
    ab = np.zeros((band + 1, n))
    _add_element_blocks(dofs, Pi, position, ab)
    if C is not None:
        _add_row_blocks(C.indptr, C.indices, C.data, position, ab)
    # a Dirichlet DOF is one more unit row of A (w_i = 0): the DOF numbering stays that of the mesh
    ab[0, position[fixed_dofs]] += 1.0
    factor = _banded_cholesky(ab)
    chain_of = label[dof_node[order]]                      # chain of every unknown, in factor order
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(n)
    for _ in range(_ITERATIONS):
        x = sla.cho_solve_banded((factor, True), x, check_finite=False)
        norm = np.sqrt(np.bincount(chain_of, weights=x * x, minlength=n_chains))
        x /= np.where(norm > 0, norm, 1.0)[chain_of]
    w = np.zeros(n)
    w[order] = x
    # ‖A w‖² per chain, term by term (no Gram matrix: its round-off would be √ε)
    residual = np.einsum("eij,ej->ei", Pi, w[dofs])
    element_chain = label[mesh.elements[:, 0]]
    energy = np.bincount(element_chain, weights=(residual * residual).sum(axis=1), minlength=n_chains)
    if C is not None:
        nonempty = np.diff(C.indptr) > 0
        r = (C @ w)[nonempty]
        row_chain = label[dof_node[C.indices[C.indptr[:-1][nonempty]]]]
        energy += np.bincount(row_chain, weights=r * r, minlength=n_chains)
    energy += np.bincount(label[dof_node[fixed_dofs]], weights=w[fixed_dofs] ** 2, minlength=n_chains)
    weight = np.bincount(label[dof_node], weights=w * w, minlength=n_chains)
    sigma = np.sqrt(energy / weight)
    out = []
    for c in np.flatnonzero(sigma <= tolerance):
        v = np.where(label[dof_node] == c, w * scale_inverse, 0.0)
        v /= np.abs(v).max()
        motion = np.sqrt(np.bincount(dof_node, weights=np.where(dof_tangent, 0.0, (w * w)), minlength=mesh.n_nodes))
        motion[label != c] = 0.0
        if mesh.element_type.has_tangents and motion.max() == 0.0:     # tangents only: rank by them
            motion = np.sqrt(np.bincount(dof_node, weights=w * w, minlength=mesh.n_nodes))
            motion[label != c] = 0.0
        moving = np.flatnonzero(motion >= 0.1 * motion.max())
        moving = moving[np.argsort(-motion[moving], kind="stable")]
        out.append(Mechanism(chain=int(c), nodes=np.flatnonzero(label == c), sigma=float(sigma[c]), mode=v,
                             moving=moving))
    return out


def _element_band(dofs, position):
    p = position[dofs]
    return int((p.max(axis=1) - p.min(axis=1)).max())


@njit
def _add_element_blocks(dofs, blocks, position, ab):
    """Add symmetric element blocks into lower banded storage: ``ab[r - c, c] += B[i, j]`` (r >= c)."""
    n_el, nd = dofs.shape
    for e in range(n_el):
        for i in range(nd):
            r = position[dofs[e, i]]
            for j in range(nd):
                c = position[dofs[e, j]]
                if r >= c:
                    ab[r - c, c] += blocks[e, i, j]


def _banded_cholesky(ab):
    """Lower banded Cholesky factor of ``G + δI``, G in ``cholesky_banded`` storage."""
    shift = _SHIFT * max(float(ab[0].max()), 1.0)
    for _ in range(4):
        shifted = ab.copy()
        shifted[0] += shift
        try:
            return sla.cholesky_banded(shifted, lower=True, check_finite=False)
        except np.linalg.LinAlgError:      # round-off made the singular Gram matrix slightly indefinite
            shift *= 100.0
    raise np.linalg.LinAlgError("mechanism probe: the Gram matrix could not be factorised")
