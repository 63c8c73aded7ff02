"""Coupling enforcement from the engine's constant operators (docs/conventions.md §1).

Global unknowns are stacked ``[d_S; d_B]`` (solid displacements first, then the beam centreline
DOFs). Because the tying constraint ``u_B − u_S = 0`` is linear in the displacements and the
operators are built once in the reference configuration, every variant below has a constant
stiffness: it is assembled once and reused in every Newton iteration.

=============  ================  ==========================================================
constraint     enforcement       what is added
=============  ================  ==========================================================
``mortar``     ``penalty``       ``ε Bᵀ κ⁻¹ B`` with ``B = [−M, D]``; ``λ = ε κ⁻¹ B d``
``mortar``     ``lagrange``      constraint rows ``B d = 0`` and multipliers λ (saddle point)
``gauss_point`` ``penalty``      ``ε Σ_g w_g Gᵀ_g G_g`` with ``G_g d = u_B(η_g) − u_S(ξ_g)``
=============  ================  ==========================================================
"""
import numpy as np
import scipy.sparse as sp

from .._config import njit
from ..elements.beam import MAX_FUNCTIONS
from ..elements.beam import shape as beam_shape
from ..elements.multiplier import multiplier as multiplier_type
from ..elements.multiplier import shape as lm_shape
from ..elements.solid import dispatch as solid_types
from ..mortar.assemble import lm_numbering


def rational_guard(solid, what):
    """ValueError naming ``what`` if ``solid`` has rational (NURBS) elements: the Gauss-point and the
    rotational couplings evaluate the polynomial part of the solid's functions only."""
    rational = sorted({d.name for d, _ in solid.blocks if d.rational})
    if rational:
        raise ValueError(f"{what}: not implemented for rational elements {rational} (NURBS spans; it would "
                         "evaluate their polynomial part only); use the mortar constraint without rotational coupling")


CONSTRAINTS = ("mortar", "gauss_point")
ENFORCEMENTS = ("penalty", "lagrange")


@njit
def _point_operator(p_beam, p_solid, eta, xi, beam_code, lengths, beam_cols, codes, conn, n_solid_nodes,
                    rows, cols, vals):
    """Scalar entries of G: row g holds H_k(η_g) at the beam columns, −N_l(ξ_g) at the solid ones."""
    H = np.empty(MAX_FUNCTIONS)
    N = np.empty(solid_types.MAX_NODES)
    k = 0
    for g in range(len(p_beam)):
        e = p_beam[g]
        beam_shape(beam_code, eta[g], lengths[e], H)
        for a in range(MAX_FUNCTIONS):
            c = beam_cols[e, a]
            if c >= 0:
                rows[k] = g
                cols[k] = n_solid_nodes + c
                vals[k] = H[a]
                k += 1
        s = p_solid[g]
        code = codes[s]
        solid_types.shape(code, xi[g], N)
        for a in range(solid_types.N_NODES[code]):
            rows[k] = g
            cols[k] = conn[s, a]
            vals[k] = -N[a]
            k += 1
    return k


@njit
def _lm_projection(p_beam, eta, weight, lm_index, n_phi, rows, cols, vals):
    """Entries Φ_j(η_g) w_g of the lumped projection from integration points to LM nodes."""
    Phi = np.empty(4)
    k = 0
    for g in range(len(p_beam)):
        lm_shape(n_phi, eta[g], Phi)
        for a in range(n_phi):
            rows[k] = lm_index[p_beam[g], a]
            cols[k] = g
            vals[k] = Phi[a] * weight[g]
            k += 1


def follow_operator(ops, beams):
    """Beam centreline DOFs that follow a given solid displacement: ``d_B ≈ P d_S``.

    The prolongation of the auxiliary-space preconditioner of the penalty system
    (:class:`mortar1d3d.solvers.linear.AuxiliarySpacePreconditioner`): a beam moved by ``P d_S``
    has almost no gap ``D d_B − M d_S``, so the stiff penalty term barely sees it.

    Parameters
    ----------
    ops : MortarOperators
        ``D`` (3 n_lm, n_B) and ``M`` (3 n_lm, 3 n_solid_nodes), in 3×3 identity blocks.
    beams : BeamMesh
        The beams of ``ops``; LM nodes ``0..n_nodes-1`` are the beam nodes (``lm_numbering``).

    Returns
    -------
    P : (n_B, 3 n_solid_nodes) scipy.sparse.csr_matrix
        In the beam mesh's own centreline DOF numbering (``[r, t]`` per Hermite node, ``r`` per
        Lagrange node).

    Notes
    -----
    Positions: ``r_k = κ_k⁻¹ (M d_S)_k``, the solid displacement averaged with the LM weight
    ``Φ_k`` of beam node k, i.e. ``D⁻¹M`` with ``D`` lumped (its row sums over the position
    columns are ``κ_k``). Tangents (Hermite): the mean over the node's elements of the chord
    derivative ``(r_b − r_a) / |X_b − X_a|``. Both reproduce a linear solid field exactly at
    interior nodes of straight, uniformly divided beams; at beam ends the half-width LM weight
    shifts the average by a third of an element. The lumped form keeps ``P`` as sparse as ``M``
    (one row per coupled node). The exact ``D⁻¹M`` (per-beam inverse, tangents as above) was
    measured on ``fibre_cube(n, 1000, 20)`` at ε = 1e3 E: 13/20 CG iterations (n = 10/20)
    against 14/19 lumped, with twice the nonzeros in the auxiliary matrix. Beam nodes that no
    integration point touched (κ = 0) do not follow (zero rows); neither do interior nodes of
    Lagrange ``line3`` elements, which have no LM node.
    """
    n_nodes = beams.n_nodes
    kappa = np.asarray(ops.kappa[:n_nodes], dtype=np.float64)
    scale = np.divide(1.0, kappa, out=np.zeros_like(kappa), where=kappa > 0)
    M = ops.M.tocsr()[0:3 * n_nodes:3, 0::3]                 # scalar rows/columns (3×3 identity blocks)
    positions = (sp.diags(scale) @ M).tocsr()
    if not beams.element_type.has_tangents:
        return expand3(positions)
    rows, cols, vals = chord_triplets(beams, np.arange(beams.n_elements))
    chord = sp.csr_matrix((vals, (rows, cols)), shape=(n_nodes, n_nodes))
    tangents = (chord @ positions).tocsr()
    # interleave to the Hermite layout: node k holds [r_k, t_k]
    order = np.empty(2 * n_nodes, dtype=np.int64)
    order[0::2] = np.arange(n_nodes)
    order[1::2] = n_nodes + np.arange(n_nodes)
    return expand3(sp.vstack([positions, tangents], format="csr")[order])


def point_triplets(ops, beams, solid):
    """The scalar entries (rows, cols, vals) of the Gauss-point constraint operator G of ``ops``'s
    integration points: row g holds H_k(η_g) at beam columns and −N_l(ξ_g) at solid ones, one column per
    node triplet: solid node l at column l, the beam mesh's centreline DOF triplet c (DOFs 3c … 3c+2) at
    ``solid.n_nodes + c``. Serial (:class:`Coupling`) and per rank (the PETSc backend)."""
    p = ops.point_fields
    nnz = ops.n_integration_points * (MAX_FUNCTIONS + solid.connectivity.shape[1])
    rows, cols, vals = np.empty(nnz, np.int64), np.empty(nnz, np.int64), np.empty(nnz)
    k = _point_operator(np.ascontiguousarray(p["beam_element"]), np.ascontiguousarray(p["solid_element"]),
                        np.ascontiguousarray(p["eta"]), np.ascontiguousarray(p["xi"]),
                        beams.element_type.code, beams.lengths, beams.function_columns(),
                        solid.element_codes, solid.connectivity, solid.n_nodes, rows, cols, vals)
    return rows[:k], cols[:k], vals[:k]


def point_projection(ops, beams):
    """Π (n_lm, n_points) scipy CSR: the entries Φ_j(η_g) w_g of the lumped projection from
    ``ops``'s integration points to the LM nodes of ``beams`` (``lm_numbering``); the Gauss-point
    penalty's line load is ``λ_j = κ_j⁻¹ Σ_g Π_jg λ_g``."""
    lm = multiplier_type(ops.lm)
    lm_index, n_lm = lm_numbering(beams, lm)
    p = ops.point_fields
    n = ops.n_integration_points * lm.n_functions
    rows, cols, vals = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    _lm_projection(np.ascontiguousarray(p["beam_element"]), np.ascontiguousarray(p["eta"]),
                   np.ascontiguousarray(p["weight"]), lm_index, lm.n_functions, rows, cols, vals)
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_lm, ops.n_integration_points))


def chord_triplets(beams, elements):
    """The Hermite tangents of :func:`follow_operator` from node positions, as (rows, cols, values):
    t_k = mean over node k's elements of the chord derivative (r_b − r_a) / |X_b − X_a|, the terms of
    ``elements`` (all of them serially; each rank its own, summed by PETSc in the distributed sweep)."""
    a, b = beams.elements[elements, 0], beams.elements[elements, 1]
    inverse_length = 1.0 / np.linalg.norm(beams.positions[b] - beams.positions[a], axis=1)
    adjacent = np.bincount(beams.elements.ravel(), minlength=beams.n_nodes).astype(np.float64)
    rows = np.concatenate([a, a, b, b])
    cols = np.concatenate([b, a, b, a])
    vals = np.concatenate([inverse_length, -inverse_length, inverse_length, -inverse_length])
    return rows, cols, vals / adjacent[rows]


def expand3(A):
    """Scalar operator → 3×3 identity blocks (scalar row/column c becomes 3c..3c+2)."""
    return sp.kron(A, sp.identity(3, format="csr"), format="csr")



def coupled_nodes(kappa, negative_kappa="drop"):
    """Which multiplier nodes are coupled: κ_j > 0 (``negative_kappa = "drop"``, the default), or
    κ_j != 0 (``"keep"``, 4C's rule for its mortar penalty). The one rule of the serial and the
    distributed paths."""
    if negative_kappa not in ("drop", "keep"):
        raise ValueError(f"negative_kappa must be 'drop' or 'keep', got {negative_kappa!r}")
    kappa = np.asarray(kappa)
    return kappa > 0.0 if negative_kappa == "drop" else kappa != 0.0

class Coupling:
    """Constant coupling operators for one beam mesh tied to one solid.

    Parameters
    ----------
    ops : MortarOperators
        From :func:`mortar1d3d.assemble_mortar` (its integration points are reused by the
        Gauss-point variant).
    beams : BeamMesh
    solid : SolidMesh
    beam_offset : int
        Index of this beam mesh's first centreline DOF in the global vector ``[d_S; d_B...]``.
    n_dofs : int
        Size of the global displacement vector.
    constraint : {"mortar", "gauss_point"}
    enforcement : {"penalty", "lagrange"}
    penalty : float
        ε, a line-spring stiffness (force / length²).
    negative_kappa : {"drop", "keep"}
        A multiplier node whose κ_j = ∫ Φ_j ds is negative (a higher-order multiplier function on a
        short piece of its element) is not coupled (``"drop"``), or coupled with its negative
        penalty weight ε / κ_j as 4C does (``"keep"``; mortar penalty only).
    """

    def __init__(self, ops, beams, solid, beam_offset, n_dofs, constraint="mortar", enforcement="penalty",
                 penalty=1.0, negative_kappa="drop"):
        if constraint not in CONSTRAINTS:
            raise ValueError(f"coupling constraint must be one of {CONSTRAINTS}, got {constraint!r}")
        if enforcement not in ENFORCEMENTS:
            raise ValueError(f"coupling enforcement must be one of {ENFORCEMENTS}, got {enforcement!r}")
        if constraint == "gauss_point" and enforcement != "penalty":
            raise ValueError("the gauss_point constraint is enforced by penalty only (one constraint per "
                             "integration point over-constrains a Lagrange multiplier field)")
        if not (np.isfinite(penalty) and penalty > 0):
            raise ValueError(f"coupling penalty must be a finite number > 0, got {penalty!r}")
        if constraint == "gauss_point":
            rational_guard(solid, "coupling.constraint = 'gauss_point'")
        self.ops, self.constraint, self.enforcement, self.penalty = ops, constraint, enforcement, float(penalty)
        self.n_dofs = n_dofs
        n_S, n_B = 3 * solid.n_nodes, beams.n_centreline_dofs
        self.n_lm = ops.n_lm
        self.coupled = coupled_nodes(ops.kappa, negative_kappa)
        self.coupled_rows = np.flatnonzero(np.repeat(self.coupled, 3))
        kinv = np.zeros(ops.n_lm)
        kinv[self.coupled] = 1.0 / ops.kappa[self.coupled]
        self.kappa_inverse = np.repeat(kinv, 3)
        # B = [−M, D] placed into the global columns
        left = sp.csr_matrix((3 * ops.n_lm, beam_offset - n_S)) if beam_offset > n_S else None
        right = sp.csr_matrix((3 * ops.n_lm, n_dofs - beam_offset - n_B)) if n_dofs > beam_offset + n_B else None
        blocks = [-ops.M] + ([left] if left is not None else []) + [ops.D] + ([right] if right is not None else [])
        self.B = sp.hstack(blocks, format="csr")
        if constraint == "gauss_point":
            self.G, self.point_weights = self._gauss_point_operator(ops, beams, solid, beam_offset, n_dofs)
            self._lm_from_points = point_projection(ops, beams)
        if enforcement == "penalty":
            if constraint == "mortar":
                K = self.B.T @ sp.diags(self.kappa_inverse) @ self.B
            else:
                K = self.G.T @ sp.diags(np.repeat(self.point_weights, 3)) @ self.G
            self.K = (self.penalty * K).tocsr()
            self.K.sum_duplicates()

    # -- operators ----------------------------------------------------------------------------
    @staticmethod
    def _gauss_point_operator(ops, beams, solid, beam_offset, n_dofs):
        rows, cols, vals = point_triplets(ops, beams, solid)
        # solid node columns stay; beam columns c → global DOF triplet (beam_offset / 3 + c)
        beam = cols >= solid.n_nodes
        cols[beam] += beam_offset // 3 - solid.n_nodes
        G = sp.csr_matrix((vals, (rows, cols)), shape=(ops.n_integration_points, n_dofs // 3))
        return expand3(G), np.ascontiguousarray(ops.point_fields["weight"])

    # -- evaluation ---------------------------------------------------------------------------
    @property
    def n_multipliers(self):
        """Number of Lagrange multiplier unknowns (coupled LM rows × 3); 0 for penalty."""
        return len(self.coupled_rows) if self.enforcement == "lagrange" else 0

    def constraint_matrix(self):
        """Rows of B for the coupled LM nodes (the saddle-point constraint block)."""
        return self.B[self.coupled_rows]

    def gap(self, d):
        """Weighted gap ``g = D d_B − M d_S``: (n_lm, 3)."""
        return (self.B @ d).reshape(-1, 3)

    def line_load(self, d, multipliers=None):
        """Coupling line load λ at the LM nodes, (n_lm, 3) (zero at uncoupled LM nodes).

        Penalty mortar: ``λ = ε κ⁻¹ g``. Lagrange: the multipliers. Gauss-point penalty: the
        point values ``ε (u_B − u_S)`` projected to the LM nodes with the lumped (κ-weighted)
        projection ``λ_j = κ_j⁻¹ Σ_g Φ_j(η_g) w_g λ_g``.
        """
        out = np.zeros(3 * self.n_lm)
        if self.enforcement == "lagrange":
            out[self.coupled_rows] = multipliers
        elif self.constraint == "mortar":
            out = self.penalty * self.kappa_inverse * (self.B @ d)
        else:
            lam_g = self.penalty * (self.G @ d).reshape(-1, 3)
            out = (self.kappa_inverse.reshape(-1, 3) * (self._lm_from_points @ lam_g)).ravel()
        return out.reshape(-1, 3)
