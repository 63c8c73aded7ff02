"""Rotational coupling of Simo–Reissner beams to the solid (penalty or Lagrange), after Steinbrecher, Popp &
Meier, "Consistent coupling of positions and rotations for embedding 1D Cosserat beams into 3D
solid volumes", Comput Mech 69 (2022).

The positional mortar coupling (:mod:`.coupling`) ties the centreline to the solid; the cross-
sections of a beam with rotations stay free to turn about it (a straight fibre's twist is a
zero-energy mode). This module ties them to a *solid triad* Λ_S, built from the solid's
deformation gradient at the centreline (:mod:`.rotational_coupling_kernel`: the polar
decomposition, or the deformed reference base vectors averaged), by the relative rotation vector
``ψ = log(Λ_B Λ_Sᵀ)`` at the integration points of the positional coupling:

- weighted constraints per rotational LM node j (``line2``/``line3`` functions Φ_j on the beam,
  independent of the positional LM): ``g_j = Σ_p Φ_j(η_p) w_p ψ_p`` (≈ ``∫ Φ_j ψ ds``),
  ``κ_j = Σ_p Φ_j(η_p) w_p``;
- penalty energy ``Π = ε/2 Σ_j κ_j⁻¹ |g_j|²`` (ε: moment per length per radian, a force), so
  the line moment at LM node j is ``λ_j = ε κ_j⁻¹ g_j``;
- residual ``∂Π/∂(u_S, θ_B) = Σ_p w_p J_pᵀ λ_p`` with ``λ_p = Σ_j Φ_j(η_p) λ_j`` and the point
  Jacobians ``J_p = ∂ψ_p/∂(u, θ)``; tangent ``ε Σ_j κ_j⁻¹ G_jᵀ G_j + Σ_p w_p ∂(J_pᵀ λ_p)``,
  ``G_j = Σ_p Φ_j w_p J_p`` (spins multiplicative, like the beam's own tangent: not symmetric
  away from equilibrium).

- point-wise penalty (``constraint="gauss_point"``, 4C's ``gauss_point_to_segment`` rotational
  coupling): ``Π = ε/2 Σ_p w_p |ψ_p|²`` at the integration points themselves, as the positional
  Gauss-point coupling does with the gap; the rows of every formula above are then the points
  (Φ → identity, κ_p = w_p). The line moments reported at the LM nodes are the lumped projection
  ``λ_j = κ_j⁻¹ Σ_p Φ_j(η_p) w_p ε ψ_p``, the same formula as with the mortar constraint.

- Lagrange enforcement (:meth:`RotationalCoupling.constraint`): multipliers λ_j at the coupled LM
  nodes (κ_j > 0) with the Lagrangian ``Σ_j λ_j · g_j``; the constraint rows are the nonlinear
  ``g_j``, their linearisation ``G_j`` the saddle point's constraint block, and ``λᵀ ∂²g`` (the
  same point sums as the penalty's geometric part) joins the stiffness block. The multipliers
  are the line moments, as ``ε κ_j⁻¹ g_j`` is with penalty, and penalty tends to them like 1/ε.

λ_j is the line moment the beam puts on the solid (the solid's on the beam is −λ_j), like the
positional coupling's line load.

Energy, residual and tangent are objective: a rigid rotation of the whole scene turns ψ and
leaves ``|ψ|`` (hence Π) unchanged.
"""
import numpy as np
import scipy.sparse as sp

from ..elements.multiplier import multiplier as multiplier_type
from ..mortar.assemble import lm_numbering
from .coupling import _lm_projection, rational_guard
from . import rotational_coupling_kernel as kernel
from . import rotational_fourc
from .simo_reissner import _lagrange_tables

__all__ = ["RotationalCoupling", "DEFAULT_PENALTY_FACTOR", "TRIADS", "LMS", "ENFORCEMENTS"]

#: default ε = DEFAULT_PENALTY_FACTOR × max GI_T / h² of the beams (h: mean beam element length):
#: the coupling over one element is then 1e3 times stiffer than the element's own torsion
DEFAULT_PENALTY_FACTOR = 1e3
TRIADS = tuple(kernel.TRIADS)
LMS = ("line2", "line3")
ENFORCEMENTS = ("penalty", "lagrange")
CONSTRAINTS = ("mortar", "gauss_point")


class RotationalCoupling:
    """Rotational coupling of one group of Simo–Reissner beams to one solid.

    Parameters
    ----------
    ops : MortarOperators
        The positional coupling's operators: their integration points (beam element, η, solid
        element, ξ, weight) are reused.
    beam : SimoReissnerBeam
        The beams' physics (rotation nodes, reference triads, ``triads(ψ)``).
    solid : SolidMesh
    rotation_offset : int
        Global index of the group's first rotation unknown (the solid's displacements are the
        global unknowns ``0 .. 3 n_solid_nodes - 1``).
    n_dofs : int
        Size of the global displacement vector.
    triad : str
        Solid triad, one of :data:`TRIADS`: ``polar``, ``deformation_gradient``,
        ``deformation_gradient_symmetric``, ``plane_y``, ``plane_z``, ``plane_average``,
        ``deformation_gradient_local_1`` … ``_3`` (:mod:`.rotational_coupling_kernel`).
    penalty : float, optional
        ε (force: moment per length per radian); default :data:`DEFAULT_PENALTY_FACTOR` × the
        largest ``GI_T`` over the squared mean element length.
    lm : {"line3", "line2"}
        Rotational multiplier functions on the beam elements. ``line3`` (default) holds as many
        rotations per element as the beam's three triads; ``line2`` leaves the twist a mesh-scale
        oscillation (docs/theory.md: 4.6e-2 torsion error against 2.5e-3 with 8 beam elements).
    enforcement : {"penalty", "lagrange"}
        Penalty (:meth:`evaluate`) or Lagrange multipliers (:meth:`constraint`, the model adds
        :attr:`n_multipliers` unknowns); ``penalty`` is then not used.
    constraint : {"mortar", "gauss_point"}
        Weighted constraints per rotational LM node (mortar) or the point-wise penalty at every
        integration point (gauss_point; penalty only). ``lm`` then only sets the functions of the
        reported line moments.
    forces : {"variational", "fourc"}
        The coupling forces: the exact gradient of the penalty energy (or of the Lagrangian), or
        4C's form, whose beam share uses the plain Lagrange functions (:mod:`.rotational_fourc`);
        the constraint, its multipliers and the line moments are the same. With ``fourc`` the
        tangent is the exact derivative of those forces (not symmetric).
    """

    def __init__(self, ops, beam, solid, rotation_offset, n_dofs, triad="polar", penalty=None, lm="line3",
                 enforcement="penalty", constraint="mortar", forces="variational"):
        if forces not in rotational_fourc.FORCES:
            raise ValueError(f"coupling.rotational.forces must be one of {rotational_fourc.FORCES}, got {forces!r}")
        if constraint not in CONSTRAINTS:
            raise ValueError(f"coupling.rotational.constraint must be one of {CONSTRAINTS}, got {constraint!r}")
        if constraint == "gauss_point" and enforcement != "penalty":
            raise ValueError("coupling.rotational: the gauss_point constraint is enforced by penalty only")
        if enforcement not in ENFORCEMENTS:
            raise ValueError(f"coupling.rotational.enforcement must be one of {ENFORCEMENTS}, got {enforcement!r}")
        if triad not in kernel.TRIADS:
            raise ValueError(f"coupling.rotational.triad must be one of {TRIADS}, got {triad!r}")
        if lm not in LMS:
            raise ValueError(f"coupling.rotational.lm must be one of {LMS}, got {lm!r}")
        rational_guard(solid, "coupling.rotational")
        if penalty is None:
            penalty = DEFAULT_PENALTY_FACTOR * float(beam.CM[:, 0].max()) / float(np.mean(beam.beams.lengths)) ** 2
        if not (np.isfinite(penalty) and penalty > 0):
            raise ValueError(f"coupling.rotational.penalty must be a finite number > 0, got {penalty!r}")
        self.beam, self.solid, self.triad, self.kind = beam, solid, triad, kernel.TRIADS[triad]
        self.penalty, self.lm, self.enforcement = float(penalty), lm, enforcement
        self.constraint_type = constraint          # (the method constraint() is the Lagrange evaluation)
        self.forces = forces
        self.rotation_offset, self.n_dofs = int(rotation_offset), int(n_dofs)
        p = ops.point_fields
        self.beam_element = np.ascontiguousarray(p["beam_element"], dtype=np.int64)
        self.eta = np.ascontiguousarray(p["eta"], dtype=np.float64)
        self.weight = np.ascontiguousarray(p["weight"], dtype=np.float64)
        solid_element = np.ascontiguousarray(p["solid_element"], dtype=np.int64)
        xi = np.ascontiguousarray(p["xi"], dtype=np.float64)
        n_pts = len(self.eta)
        self.n_points = n_pts
        m = kernel.solid_types.MAX_NODES
        self.G = np.zeros((n_pts, m, 3))
        self.nodes = np.zeros((n_pts, m), dtype=np.int64)
        self.n_local = np.zeros(n_pts, dtype=np.int64)
        X = np.ascontiguousarray(solid.points, dtype=np.float64)
        kernel.reference_gradients(solid.element_codes, solid.connectivity, X, solid_element, xi, self.G, self.nodes,
                                   self.n_local)
        # only as many node slots as the largest element has: the local Hessian's chain to the nodes
        # costs (3 slots)² per point, 11x more with hex8 in 27 slots than in 8 (MAX_NODES is larger still)
        used = max(int(self.n_local.max(initial=0)), 1)
        self.G, self.nodes = np.ascontiguousarray(self.G[:, :used]), np.ascontiguousarray(self.nodes[:, :used])
        self.lag = _lagrange_tables(self.eta)[0]
        self.rotation_nodes = beam.rotation_nodes
        self.L0 = np.empty((n_pts, 3, 3))
        status = np.empty(n_pts, dtype=np.int64)
        kernel.reference_triads_at(beam.triads0, self.rotation_nodes, self.beam_element, self.lag, self.L0, status)
        # rotational multipliers: Φ_j(η_p) and κ_j
        lm_t = multiplier_type(lm)
        index, self.n_lm = lm_numbering(beam.beams, lm_t)
        self.lm_index = index
        # Φ_j(η_p) by the positional coupling's kernel (unit weights: the weights enter where used)
        n = n_pts * lm_t.n_functions
        rows, cols, vals = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
        _lm_projection(self.beam_element, self.eta, np.ones(n_pts), np.ascontiguousarray(index), lm_t.n_functions,
                       rows, cols, vals)
        self.Phi = sp.csr_matrix((vals, (rows, cols)), shape=(self.n_lm, n_pts))
        self.kappa = np.asarray(self.Phi @ self.weight).ravel()
        self.kappa_inverse = np.divide(1.0, self.kappa, out=np.zeros_like(self.kappa), where=self.kappa > 0)
        # LM nodes some integration point touched: only they carry a Lagrange multiplier (three rows each)
        self.coupled_rows = np.flatnonzero(np.repeat(self.kappa > 0, 3))
        # the rows of the constraint: the LM functions (mortar), or every point on its own
        if constraint == "gauss_point":
            self.rows = sp.identity(n_pts, format="csr")
            self.rows_kappa_inverse = np.divide(1.0, self.weight, out=np.zeros_like(self.weight),
                                                where=self.weight > 0)
        else:
            self.rows, self.rows_kappa_inverse = self.Phi, self.kappa_inverse
        self.X = X
        self.n_evaluations = 0

    # -- state -------------------------------------------------------------------------------------
    def _columns(self):
        """Global unknown of every local column per point (n_pts, 3 m + 9; m: node slots, the most
        nodes of the solid elements touched): three per solid node slot (-1 for slots the element
        does not have), then the nine spins."""
        m = self.nodes.shape[1]
        cols = (3 * self.nodes[:, :, None] + np.arange(3)).reshape(self.n_points, 3 * m)
        cols[np.repeat(np.arange(m)[None, :] >= self.n_local[:, None], 3, axis=1)] = -1
        rot = (self.rotation_offset + 3 * self.rotation_nodes[self.beam_element][:, :, None]
               + np.arange(3)).reshape(-1, 9)
        return np.hstack([cols, rot])

    def _local_jacobian(self, J):
        """``∂ψ/∂(F, θ)`` (n_pts, 3, 18) → ``∂ψ/∂(u, θ)`` (n_pts, 3, 3 m + 9), with
        ``∂F_ij/∂u_ak = δ_ik G_aj``."""
        n = self.n_points
        Ju = np.einsum("prij,paj->prai", J[:, :, :9].reshape(n, 3, 3, 3), self.G).reshape(n, 3, -1)
        return np.concatenate([Ju, J[:, :, 9:]], axis=2)

    def _local_hessian(self, H):
        """``∂²/∂(F, θ)²`` (n_pts, 18, 18) → ``∂²/∂(u, θ)²`` (n_pts, 3 m + 9, same)."""
        n, G = self.n_points, self.G
        HFF = H[:, :9, :9].reshape(n, 3, 3, 3, 3)
        uu = np.einsum("pijkl,paj,pbl->paibk", HFF, G, G).reshape(n, 3 * G.shape[1], 3 * G.shape[1])
        ut = np.einsum("pijt,paj->pait", H[:, :9, 9:].reshape(n, 3, 3, 9), G).reshape(n, -1, 9)
        tu = np.einsum("ptij,paj->ptai", H[:, 9:, :9].reshape(n, 9, 3, 3), G).reshape(n, 9, -1)
        return np.concatenate([np.concatenate([uu, ut], axis=2), np.concatenate([tu, H[:, 9:, 9:]], axis=2)], axis=1)

    def _run(self, u_solid, psi, want):
        x = np.ascontiguousarray(self.X + np.asarray(u_solid, dtype=float).reshape(-1, 3))
        triads = self.beam.triads(psi)
        psi_p = np.zeros((self.n_points, 3))
        J = np.zeros((self.n_points, 3, 18) if want else (0, 3, 18))
        status = np.empty(self.n_points, dtype=np.int64)
        kernel.jacobian_range(self.kind, x, self.nodes, self.n_local, self.G, self.L0, triads, self.rotation_nodes,
                              self.beam_element, self.lag, want, psi_p, J, status)
        self._check(status, psi_p)
        return x, triads, psi_p, J

    @staticmethod
    def _check(status, psi_p):
        if np.any(status != kernel.OK) or not np.isfinite(psi_p).all():
            raise FloatingPointError("rotational coupling: the solid triad or the beam triad could not be formed at "
                                     f"{int(np.count_nonzero(status != kernel.OK))} integration points (the polar "
                                     "decomposition did not converge, or a beam element turned too far)")

    # -- public ------------------------------------------------------------------------------------
    def relative_rotations(self, u_solid, psi):
        """ψ = log(Λ_B Λ_Sᵀ) (n_points, 3) at the integration points."""
        return self._run(u_solid, psi, False)[2]

    def weighted_gap(self, u_solid, psi):
        """``g_j`` (n_lm, 3): the relative rotations weighted with the rotational LM functions."""
        return np.asarray(self.Phi @ (self.weight[:, None] * self.relative_rotations(u_solid, psi)))

    @property
    def n_multipliers(self):
        """Number of Lagrange multiplier unknowns (three per coupled LM node); 0 for penalty."""
        return len(self.coupled_rows) if self.enforcement == "lagrange" else 0

    def line_moment(self, u_solid, psi, multipliers=None, linear=False):
        """Coupling line moments λ_j (n_lm, 3) at the rotational LM nodes (spatial, moment per length).

        Penalty: ``λ_j = ε κ_j⁻¹ g_j``; with ``linear=True`` (a linear analysis) ``g_j`` is the
        constraint linearised at the reference state, ``G(0) [u_S; ψ]``, the one that analysis
        solves with (the nonlinear ``g_j`` of its small-rotation solution is not zero but of
        the third order in the rotations, which ε would magnify). Lagrange: the
        ``multipliers`` (:attr:`n_multipliers`, three per coupled LM node), zero at the LM nodes
        no integration point touched.
        """
        if self.enforcement == "lagrange":
            out = np.zeros(3 * self.n_lm)
            out[self.coupled_rows] = multipliers
            return out.reshape(-1, 3)
        if linear:
            d = np.zeros(self.n_dofs)
            d[:self.X.size] = u_solid
            psi = np.asarray(psi, dtype=float).ravel()
            d[self.rotation_offset: self.rotation_offset + psi.size] = psi
            gap = (self.reference_rows() @ d).reshape(-1, 3)
            if self.constraint_type == "gauss_point":
                gap = self.Phi @ gap
        else:
            gap = self.weighted_gap(u_solid, psi)
        return self.penalty * self.kappa_inverse[:, None] * gap

    def reference_rows(self):
        """The constraint's linearisation ``G`` at the reference state (3 n_rows, n_dofs, csr; the
        rows of :attr:`rows`), computed once."""
        if getattr(self, "_reference_rows", None) is None:
            n_rot = self.beam.n_rotation_nodes
            self._reference_rows = self._linearise(np.zeros(self.X.size), np.zeros((n_rot, 3)),
                                                   lambda g: np.zeros_like(g), True)[2]
        return self._reference_rows

    def energy(self, u_solid, psi):
        """Penalty energy ``ε/2 Σ_j κ_j⁻¹ |g_j|²`` (gauss_point: ``ε/2 Σ_p w_p |ψ_p|²``)."""
        g = np.asarray(self.rows @ (self.weight[:, None] * self.relative_rotations(u_solid, psi)))
        return 0.5 * self.penalty * float(np.sum(self.rows_kappa_inverse[:, None] * g * g))

    def _linearise(self, u_solid, psi, moments, tangent):
        """What both enforcements share: the weighted gaps ``g`` (n_rows, 3), the forces ``Gᵀλ``
        (n_dofs,) of the line moments ``λ = moments(g)`` (n_rows, 3), and with ``tangent`` the
        constraint's linearisation ``G`` (3 n_rows, n_dofs, csr) and ``λᵀ ∂²g`` (n_dofs, n_dofs,
        csr). Rows: the LM nodes (mortar) or the points (gauss_point), :attr:`rows`. Last, the
        rows of the forces' own Jacobians ``Σ_p R_jp w_p Jf_p`` (``G`` itself for variational forces;
        with ``forces="fourc"`` ``r`` and ``λᵀ ∂²g`` are those of 4C's forces)."""
        state = self.point_state(u_solid, psi)
        return self.linearised(state, moments(state[-1]), tangent)

    def point_state(self, u_solid, psi):
        """The first half of :meth:`_linearise`: the points' relative rotations and Jacobians at
        ``(u_solid, psi)``, and last the weighted gaps ``g`` (n_rows, 3). A caller that sums ``g``
        with other parts of the same rows (the same LM node on two processes) forms the line
        moments from the sum and hands them to :meth:`linearised`."""
        self.n_evaluations += 1
        x, triads, psi_p, J18 = self._run(u_solid, psi, True)
        J = self._local_jacobian(J18)
        cols = self._columns()
        g = np.asarray(self.rows @ (self.weight[:, None] * psi_p))
        return x, triads, psi_p, J, cols, g

    def linearised(self, state, lam_j, tangent):
        """The second half of :meth:`_linearise`, with the line moments ``lam_j`` (n_rows, 3) of
        the rows: what :meth:`_linearise` returns."""
        x, triads, psi_p, J, cols, g = state
        lam_p = np.asarray(self.rows.T @ lam_j)                                      # (n_pts, 3)
        used = cols >= 0
        Jf = J
        if self.forces == "fourc":
            # 4C's forces: the beam columns L_k T⁻ᵀ(ψ_p) instead of ∂ψ_p/∂θ_k = T⁻¹(ψ_p) Ĩ_k
            Jf = J.copy()
            Jf[:, :, -9:] = rotational_fourc.beam_columns(psi_p, self.lag)
        local = np.einsum("pic,pi->pc", Jf, lam_p) * self.weight[:, None]
        r = np.bincount(cols[used], weights=local[used], minlength=self.n_dofs)
        if not tangent:
            return g, r, None, None, None
        # G_j = Σ_p Φ_j w_p J_p (3 n_rows, n_dofs), and the same rows of the force Jacobians
        Gm = self._row_sums(J, cols)
        Gf = Gm if Jf is J else self._row_sums(Jf, cols)
        H = np.zeros((self.n_points, 18, 18))
        status = np.empty(self.n_points, dtype=np.int64)
        kernel.hessian_range(self.kind, x, self.nodes, self.n_local, self.G, self.L0, triads, self.rotation_nodes,
                             self.beam_element, self.lag, np.ascontiguousarray(lam_p), H, status)
        self._check(status, psi_p)
        H = self._local_hessian(H * self.weight[:, None, None])
        if self.forces == "fourc":
            # rows of the beam spins: ∂(w_p L_k T⁻¹(ψ_p) λ_p)/∂(u, θ) at fixed λ = w_p L_k ∂(T⁻¹λ_p)/∂ψ J_p
            DJ = np.einsum("pab,pbc->pac", rotational_fourc.inverse_jacobian_derivative(psi_p, lam_p), J)
            H[:, -9:, :] = (self.weight[:, None, None, None] * self.lag[:, :, None, None]
                            * DJ[:, None, :, :]).reshape(self.n_points, 9, -1)
        both = used[:, :, None] & used[:, None, :]
        ri = np.broadcast_to(cols[:, :, None], H.shape)[both]
        ci = np.broadcast_to(cols[:, None, :], H.shape)[both]
        return g, r, Gm, sp.csr_matrix((H[both], (ri, ci)), shape=(self.n_dofs, self.n_dofs)), Gf

    def _row_sums(self, J, cols, n_cols=None):
        """``Σ_p R_jp w_p J_p`` (3 n_rows, n_cols (default n_dofs), csr) for the constraint rows R
        (:attr:`rows`); ``cols[p]`` the column of each of J_p's columns, -1 for none."""
        Phi = self.rows.tocoo()
        k, pts = Phi.row, Phi.col
        scale = Phi.data * self.weight[pts]
        rows = (3 * k[:, None, None] + np.arange(3)[None, :, None]) + 0 * cols[pts][:, None, :]
        vals = scale[:, None, None] * J[pts]
        cc = np.broadcast_to(cols[pts][:, None, :], vals.shape)
        mask = cc >= 0
        return sp.csr_matrix((vals[mask], (rows[mask], cc[mask])),
                             shape=(3 * self.rows.shape[0], self.n_dofs if n_cols is None else n_cols))

    def evaluate(self, u_solid, psi, tangent=True):
        """Penalty: residual (n_dofs,) and tangent (n_dofs, n_dofs, csr, or None) in the global
        displacement unknowns: solid displacements (additive) and the group's rotation spins
        (multiplicative).

        Parameters
        ----------
        u_solid : (3 n_solid_nodes,) solid displacements.
        psi : (n_rotation_nodes, 3) total rotation vectors of the group.
        """
        kinv = self.rows_kappa_inverse
        _, r, Gm, K_lam, Gf = self._linearise(u_solid, psi, lambda g: self.penalty * kinv[:, None] * g, tangent)
        if not tangent:
            return r, None
        return r, self.penalty_tangent(Gm, K_lam, Gf)

    def penalty_tangent(self, Gm, K_lam, Gf):
        """The penalty's tangent from what :meth:`linearised` returns: ε Gᵀ κ⁻¹ G, plus the
        geometric part of the constraint's second derivative (fourc forces: their rows Gf instead
        of the left G, and their own second part)."""
        K = self.penalty * (Gf.T @ sp.diags(np.repeat(self.rows_kappa_inverse, 3)) @ Gm)
        K = K + K_lam
        return K.tocsr()

    def constraint(self, u_solid, psi, multipliers, tangent=True):
        """Lagrange: the multipliers' forces, the constraint rows and their linearisation.

        The constraint ``g_j(u_S, θ_B) = 0`` is nonlinear; with multipliers λ (line moments, three
        per coupled LM node, :attr:`n_multipliers`) the Lagrangian adds ``Σ_j λ_j · g_j``.

        Returns
        -------
        r : (n_dofs,) ``Gᵀλ``, the moments the multipliers put on the solid and the beam's spins.
        c : (n_multipliers,) the constraint values ``g_j`` at the coupled LM nodes.
        G : (n_multipliers, n_dofs) csr or None
            ``∂g/∂(u, θ)`` (spins multiplicative): the constraint rows of the saddle point.
        K : (n_dofs, n_dofs) csr or None
            ``λᵀ ∂²g``, the multipliers' part of the tangent.
        """
        lam = np.zeros(3 * self.n_lm)
        lam[self.coupled_rows] = multipliers
        g, r, Gm, K, _ = self._linearise(u_solid, psi, lambda _: lam.reshape(-1, 3), tangent)
        c = g.ravel()[self.coupled_rows]
        return r, c, (Gm[self.coupled_rows] if tangent else None), K

    def beam_rows(self):
        """Linearised constraint rows on the group's rotation spins at the reference state, solid
        held: ``G_j`` restricted to the rotation columns (3 n_lm, 3 n_rotation_nodes), for the
        zero-energy-mode check."""
        n_rot = self.beam.n_rotation_nodes
        J = self._run(np.zeros(self.X.size), np.zeros((n_rot, 3)), True)[3][:, :, 9:]
        cols = self._columns()[:, -9:] - self.rotation_offset
        return self._row_sums(J, cols, 3 * n_rot)
