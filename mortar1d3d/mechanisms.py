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
_ITERATIONS = 4
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


def _dof_layout(mesh):
    """Per centreline DOF: its node and whether it is a tangent component."""
    if mesh.element_type.name == "hermite":
        triplet = np.arange(2 * mesh.n_nodes)
        node, tangent = triplet // 2, triplet % 2 == 1
    else:
        node, tangent = np.arange(mesh.n_nodes), np.zeros(mesh.n_nodes, dtype=bool)
    return np.repeat(node, 3), np.repeat(tangent, 3)


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
    cols = cols[:, cols[0] >= 0]                           # line: 2 columns, Hermite: [r1, t1, r2, t2]
    n_el, n_f = cols.shape
    dofs = (3 * cols[:, :, None] + np.arange(3)).reshape(n_el, 3 * n_f)
    if mesh.element_type.name == "hermite":
        node, tangent = cols // 2, cols % 2 == 1
        vectors = np.where(tangent[:, :, None], mesh.tangents[node], mesh.positions[node])
    else:
        node, tangent = cols, np.zeros(cols.shape, dtype=bool)
        vectors = mesh.positions[node]
    a, b = mesh.positions[mesh.elements[:, 0]], mesh.positions[mesh.elements[:, 1]]
    chord = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    seed = np.where(np.abs(chord[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    n1 = np.cross(chord, seed)
    n1 /= np.linalg.norm(n1, axis=1)[:, None]
    n2 = np.cross(chord, n1)
    length = scale[node]                                   # (n_el, n_f)
    # a rigid motion a + ω × (x − c) moves positions by it / ℓ and turns tangents by ω × t
    lever = np.where(tangent[:, :, None], vectors, (vectors - 0.5 * (a + b)[:, None, :]) / length[:, :, None])
    R = np.zeros((n_el, n_f, 3, 5))
    for k in range(3):
        R[:, :, k, k] = np.where(tangent, 0.0, 1.0 / length)
    R[:, :, :, 3] = np.cross(n1[:, None, :], lever)
    R[:, :, :, 4] = np.cross(n2[:, None, :], lever)
    projectors = np.empty((n_el, 3 * n_f, 3 * n_f))
    _complement_projectors(R.reshape(n_el, 3 * n_f, 5), projectors)
    return dofs, projectors


@njit
def _complement_projectors(R, out):
    """``out[e] = I − U Uᵀ`` with U the columns of ``R[e]`` orthonormalised (modified Gram–Schmidt)."""
    n_el, nd, m = R.shape
    U = np.empty((nd, m))
    for e in range(n_el):
        for k in range(m):
            for i in range(nd):
                U[i, k] = R[e, i, k]
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
                v = -U[i, 0] * U[j, 0]
                for k in range(1, m):
                    v -= U[i, k] * U[j, k]
                out[e, i, j] = v + (1.0 if i == j else 0.0)


def _coupling_rows(rows, scale_inverse):
    """Coupling rows in dimensionless DOFs, each of unit length; empty rows dropped."""
    C = (sp.csr_matrix(rows) @ sp.diags(scale_inverse)).tocsr()
    norm = np.sqrt(np.asarray(C.multiply(C).sum(axis=1)).ravel())
    keep = norm > 0
    return (sp.diags(1.0 / norm[keep]) @ C[keep]).tocsr()


def find_mechanisms(mesh, coupling_rows=None, fixed=None, tolerance=MECHANISM_TOLERANCE, seed=0):
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

    Returns
    -------
    list of Mechanism
        One per chain that can move at no cost (its smallest mode), in chain order.
    """
    n = mesh.n_centreline_dofs
    fixed = np.zeros(n, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    n_chains, label = chains(mesh)
    dof_node, dof_tangent = _dof_layout(mesh)
    node_scale = _node_scale(mesh)
    scale_inverse = np.where(dof_tangent, 1.0, node_scale[dof_node])      # v = scale_inverse * w
    dofs, Pi = _element_projectors(mesh, node_scale)
    C = None
    extra_rows, extra_cols, extra_vals = [], [], []
    if coupling_rows is not None and coupling_rows.shape[0]:
        C = _coupling_rows(coupling_rows, scale_inverse)
        CtC = sp.tril(C.T @ C).tocoo()
        extra_rows.append(CtC.row)
        extra_cols.append(CtC.col)
        extra_vals.append(CtC.data)
    # a Dirichlet DOF is one more unit row of A (w_i = 0): the DOF numbering stays that of the mesh
    extra_rows.append(np.flatnonzero(fixed))
    extra_cols.append(extra_rows[-1])
    extra_vals.append(np.ones(len(extra_rows[-1])))
    extra_rows, extra_cols = np.concatenate(extra_rows), np.concatenate(extra_cols)
    extra_vals = np.concatenate(extra_vals)
    # banded Cholesky of the Gram matrix: chains numbered along their length (every generator and
    # curve spec does that) give a narrow band; otherwise reverse Cuthill–McKee first
    order = np.arange(n)
    band = max(int((dofs.max(axis=1) - dofs.min(axis=1)).max()),
               int(np.abs(extra_rows - extra_cols).max()) if len(extra_rows) else 0)
    if band > _NATURAL_BAND:
        nd = dofs.shape[1]
        pattern = sp.csr_matrix((np.ones(dofs.size * nd), (np.repeat(dofs, nd, axis=1).ravel(),
                                                           np.tile(dofs, (1, nd)).ravel())), shape=(n, n))
        pattern = pattern + sp.csr_matrix((np.ones(len(extra_rows)), (extra_rows, extra_cols)), shape=(n, n))
        order = reverse_cuthill_mckee((pattern + pattern.T).tocsr(), symmetric_mode=True)
    position = np.empty(n, dtype=np.int64)
    position[order] = np.arange(n)
    e_rows, e_cols = position[extra_rows], position[extra_cols]
    band = max(_element_band(dofs, position), int(np.abs(e_rows - e_cols).max()) if len(e_rows) else 0)
    ab = np.zeros((band + 1, n))
    _add_element_blocks(dofs, Pi, position, ab)
    lower, upper = np.maximum(e_rows, e_cols), np.minimum(e_rows, e_cols)
    np.add.at(ab, (lower - upper, upper), extra_vals)
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
        r = C @ w
        row_chain = label[dof_node[C.indices[C.indptr[:-1]]]]
        energy += np.bincount(row_chain, weights=r * r, minlength=n_chains)
    energy += np.bincount(label[dof_node[fixed]], weights=w[fixed] ** 2, minlength=n_chains)
    weight = np.bincount(label[dof_node], weights=w * w, minlength=n_chains)
    sigma = np.sqrt(energy / weight)
    out = []
    for c in np.flatnonzero(sigma <= tolerance):
        v = np.where(label[dof_node] == c, w * scale_inverse, 0.0)
        v /= np.abs(v).max()
        motion = np.sqrt(np.bincount(dof_node, weights=np.where(dof_tangent, 0.0, (w * w)), minlength=mesh.n_nodes))
        motion[label != c] = 0.0
        if mesh.element_type.name == "hermite" and motion.max() == 0.0:     # tangents only: rank by them
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
