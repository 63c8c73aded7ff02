"""The solution monitor: what each variant's operators do to the displacement of a linear solve.

:class:`MonitorProblem` is the linear problem of one study scene (a clamped, self-weighted cube
with stiff penalty-coupled fibres), condensed onto the DOFs the coupling reaches;
:class:`ClampedSolid` its factorised solid, shared by the scenes on one mesh;
:func:`solution_monitor` and :func:`monitor_error` the quantity and its error.
"""
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..model import Model
from ..scene import Scene
from ..solvers.linear import _factorize, rigid_body_modes

#: the linear problem of the solution monitor (see :class:`MonitorProblem`)
MONITOR_SOLID = {"E": 1.0, "nu": 0.3}
MONITOR_BEAM = {"E": 1000.0, "radius": 0.02}
MONITOR_BODY_FORCE = (0.0, 0.0, -1.0)


class ClampedSolid:
    """The clamped solid of the monitor problem: ``K_SS`` factorised once, flexibility on demand.

    Shared by the :class:`MonitorProblem` of every scene on the same solid mesh (the study's
    scenes of one kind differ in their fibres only), so that the factorisation and the columns
    of the flexibility are computed once per mesh.

    Parameters
    ----------
    K : (n_S, n_S) scipy.sparse matrix
        Stiffness of the solid (all DOFs).
    force : (n_S,) array
        Load on the solid DOFs.
    fixed : (n_S,) bool array
        Clamped DOFs (displacement 0).
    points : (n_nodes, 3) array
        The mesh's nodes (to check that a problem is on the same mesh).

    Attributes
    ----------
    u0 : (n_S,) float64
        ``K_SS⁻¹ f_S``: the solid's displacement without the beams.
    dofs : (n_I,) int64
        Free DOFs whose flexibility columns are known (in the order of ``F``).
    F : (n_I, n_I) float64
        ``(K_SS⁻¹)`` restricted to ``dofs`` (symmetric).
    n_columns_solved : int
        Columns of ``K_SS⁻¹`` computed so far (the cost of this object).
    """

    #: flexibility columns solved per call of the factorisation (bounds the dense temporaries)
    CHUNK = 256

    def __init__(self, K, force, fixed, points):
        self.fixed = np.asarray(fixed, dtype=bool)
        self.points = np.asarray(points)
        self.free = np.flatnonzero(~self.fixed)
        self._lu = _factorize(K.tocsr()[self.free][:, self.free], symmetric_positive=True)
        self.u0 = np.zeros(len(self.fixed))
        self.u0[self.free] = self._lu.solve(np.asarray(force, dtype=np.float64)[self.free])
        self.dofs = np.zeros(0, dtype=np.int64)
        self.F = np.zeros((0, 0))
        self._position = np.full(len(self.fixed), -1, dtype=np.int64)
        self.n_columns_solved = 0

    def flexibility(self, dofs):
        """``F[dofs][:, dofs]`` for free ``dofs``: solves ``K_SS x = e_k`` for the columns not known yet."""
        dofs = np.asarray(dofs, dtype=np.int64)
        if self.fixed[dofs].any():
            raise ValueError("ClampedSolid.flexibility: clamped DOFs have no flexibility (their displacement is 0)")
        new = np.unique(dofs[self._position[dofs] < 0])
        if new.size:
            old = self.dofs
            all_dofs = np.concatenate([old, new])
            F = np.empty((len(all_dofs),) * 2)
            F[: len(old), : len(old)] = self.F
            where = np.searchsorted(self.free, new)
            for start in range(0, len(new), self.CHUNK):              # bounded temporaries (n_S x CHUNK)
                cols = slice(start, min(start + self.CHUNK, len(new)))
                E = np.zeros((len(self.free), cols.stop - cols.start))
                E[where[cols], np.arange(cols.stop - cols.start)] = 1.0
                X = np.zeros((len(self.fixed), E.shape[1]))
                X[self.free] = self._lu.solve(E)                        # K_SS⁻¹ e_new
                F[:, len(old) + cols.start: len(old) + cols.stop] = X[all_dofs]
            self.n_columns_solved += len(new)
            F[len(old):, : len(old)] = F[: len(old), len(old):].T
            block = F[len(old):, len(old):]
            F[len(old):, len(old):] = 0.5 * (block + block.T)           # symmetric to round-off
            self.dofs = all_dofs
            self.F = F
            self._position[new] = len(old) + np.arange(len(new))
        k = self._position[dofs]
        return self.F[np.ix_(k, k)]


class MonitorProblem:
    """The linear problem behind the solution monitor of one study scene.

    The unit cube of the scene, small-strain linear elastic (``E = 1, ν = 0.3``), clamped on
    ``x = 0`` and loaded by its own weight (body force ``(0, 0, -1)``): a cantilever that bends.
    The fibres are torsion-free Hermite beams, ``E_B = 1000`` and radius 0.02 (``EA ≈ 1.26``,
    comparable with the axial stiffness of the cube, so the coupling transfers real force),
    tied to the solid by penalty mortar coupling with ``ε = 1e3 E`` (the library's default).
    The fibres must be straight (the scenes of :data:`MONITOR_KINDS`): curved ones are a
    SceneError of the torsion-free beam.

    The solid and beam stiffness are assembled through :class:`~mortar1d3d.model.Model` (given
    the reference operators, so nothing is integrated again) and the clamped solid is
    factorised once (:class:`ClampedSolid`, shareable between scenes on the same mesh);
    :meth:`displacement` then solves the coupled problem for any operators ``D, M, κ`` of the
    scene with a small dense system (Notes).

    Parameters
    ----------
    beams : BeamMesh (Hermite), solid : SolidMesh
        The scene (:func:`build_scene`).
    reference : MortarOperators
        The study's reference operators of the scene: they choose the monitor point and are
        the operators of the model's own coupling (:attr:`scene`).
    penalty : float, optional
        ε; default ``DEFAULT_PENALTY_FACTOR * E`` (1e3).
    clamped : ClampedSolid, optional
        The factorised solid of another MonitorProblem on the same mesh (``.clamped``).

    Attributes
    ----------
    scene : Scene
        The problem as a scene (:func:`monitor_scene`): ``mortar1d3d.solve`` solves the same
        system with its own operators.
    beam_node, solid_node : int
        The monitor point: the beam node with the largest reference κ (the most coupled one)
        and the free solid node nearest to it.
    clamped : ClampedSolid

    Notes
    -----
    **Why penalty, not Lagrange multipliers.** With multipliers the saddle point is singular
    whenever a variant has fewer independent integration points than LM nodes:
    ``B = [-M, D] = P G`` with ``P`` (LM nodes × points) has rank <= the number of points, so
    element-based integration with one point per beam element (``n_el`` points, ``n_el + 1``
    LM nodes per fibre) has dependent constraint rows. The cheapest variants of the study are
    among those to measure, so the monitor uses the library's default penalty enforcement,
    which is well posed whatever the rank of ``B``. The penalty solution depends on ε, but
    every variant and the reference are solved with the same ε, so the error measures the
    operators alone. What no enforcement fixes is a fibre the coupling does not hold against
    rigid motion at all (:meth:`free_motions`); that unloaded motion is set to zero.

    **Condensation.** With ``λ = ε κ⁻¹ (D u_B − M u_S)`` on the coupled LM rows the penalty
    system reads ``K_SS u_S − Mᵀλ = f_S``, ``K_BB u_B + Dᵀλ = f_B``,
    ``D u_B − M u_S − (κ/ε) λ = 0``. Eliminating ``u_S = u_0 + K_SS⁻¹ Mᵀ λ``
    (``u_0 = K_SS⁻¹ f_S``) leaves, per variant,

        [[K_BB, Dᵀ], [D, −(M F Mᵀ + κ/ε)]] [u_B; λ] = [f_B; M u_0],

    with the solid's flexibility ``F = K_SS⁻¹`` restricted to the DOFs that M reaches. The
    system has beam DOFs + 3 × coupled LM nodes unknowns, a few hundred in the study: dense.
    It is the system that :func:`mortar1d3d.model.solve` solves for :attr:`scene` (tested to
    round-off).
    """

    def __init__(self, beams, solid, reference, penalty=None, clamped=None):
        self.scene = monitor_scene(beams, solid, reference, penalty)
        model = Model(self.scene).prepare(operators=[reference])
        self.penalty = model.penalty
        g = model.groups[0]
        n_S = 3 * solid.n_nodes
        if (model.fixed_dofs >= n_S).any():
            raise ValueError("MonitorProblem: the monitor scene fixes beam DOFs; it must fix solid DOFs only")
        z0 = np.zeros(model.n_unknowns)
        force = -model.residual(z0, 1.0, tangent=False)[0]        # dead load − internal forces at rest
        _, K_BB = g.physics.evaluate(np.zeros(g.mesh.n_centreline_dofs), tangent=True)
        self.K_BB = K_BB.toarray()
        self.f_B = force[g.dof_offset: g.dof_offset + g.mesh.n_centreline_dofs]
        if clamped is None:
            fixed = np.zeros(n_S, dtype=bool)
            fixed[model.fixed_dofs] = True
            _, K_SS = model.solid_physics.evaluate(np.zeros(n_S), tangent=True)
            clamped = ClampedSolid(K_SS, force[:n_S], fixed, solid.points)
        elif clamped.points.shape != solid.points.shape or not np.array_equal(clamped.points, solid.points):
            raise ValueError("MonitorProblem: clamped belongs to another solid mesh")
        self.clamped = clamped
        kappa_node = np.asarray(reference.kappa[: beams.n_nodes])       # LM nodes 0..n_nodes-1 = beam nodes
        self.beam_node = int(np.argmax(kappa_node))
        if kappa_node[self.beam_node] <= 0:
            raise ValueError("MonitorProblem: no beam node is coupled in the reference operators")
        free_nodes = np.flatnonzero(~clamped.fixed.reshape(-1, 3).all(axis=1))
        dist = np.linalg.norm(solid.points[free_nodes] - beams.positions[self.beam_node], axis=1)
        self.solid_node = int(free_nodes[np.argmin(dist)])
        self._fibre_modes = self._rigid_modes(g)
        self.n_solves = 0
        self.held = True                 # whether the last solve's coupling held every fibre

    @staticmethod
    def _rigid_modes(group):
        """Per fibre (connected chain of beam elements): its local beam DOFs and an orthonormal
        basis of its rigid-body motions (tangents rotate with it)."""
        mesh = group.mesh
        adjacency = sp.coo_matrix((np.ones(mesh.n_elements), (mesh.elements[:, 0], mesh.elements[:, 1])),
                                  shape=(mesh.n_nodes, mesh.n_nodes))
        n_fibres, label = connected_components(adjacency, directed=False)
        out = []
        for f in range(n_fibres):
            nodes = np.flatnonzero(label == f)
            local = (6 * nodes[:, None] + np.arange(6)).ravel()
            # triplets per node: position, tangent (the layout of the beam DOFs)
            triplets = np.stack([mesh.positions[nodes], mesh.tangents[nodes]], axis=1).reshape(-1, 3)
            R = rigid_body_modes(triplets, np.tile([False, True], len(nodes)))
            U, sv, _ = np.linalg.svd(R, full_matrices=False)
            out.append((local, U[:, sv > 1e-10 * sv[0]]))
        return out

    def free_motions(self, D, kappa):
        """Rigid motions of the fibres that the coupling ``D`` (rows with κ > 0) does not stop.

        Each fibre is held against rigid motion by its coupled LM rows alone (the beam stiffness
        does not resist rigid motions). Where they tie the fibre at one point only (element-based
        integration with a single point inside the solid), it can rotate about that point.

        Returns
        -------
        (n_beam_dofs, k) float64
            Orthonormal columns spanning the free motions (k = 0 if every fibre is held).
        """
        rows = np.flatnonzero(np.repeat(np.asarray(kappa) > 0.0, 3))
        Dc = D.tocsr()[rows]
        held = [np.asarray(Dc[:, local] @ Q) for local, Q in self._fibre_modes]   # the coupling seen by each mode
        scale = max((np.linalg.norm(X, 2) for X in held), default=0.0)
        out = []
        for (local, Q), X in zip(self._fibre_modes, held):
            _, sv, Vt = np.linalg.svd(X, full_matrices=X.shape[0] < X.shape[1])     # all of Vt, U thin
            sv = np.concatenate([sv, np.zeros(Q.shape[1] - len(sv))])
            null = Vt[sv <= 1e-8 * scale]
            if len(null):
                Z = np.zeros((self.K_BB.shape[0], len(null)))
                Z[local] = Q @ null.T
                out.append(Z)
        return np.hstack(out) if out else np.zeros((self.K_BB.shape[0], 0))

    def displacement(self, D, M, kappa):
        """Displacements at the monitor point with operators ``D, M, κ`` of this scene.

        Returns
        -------
        (6,) float64
            ``[u_B, u_S]``: the displacement of :attr:`beam_node` and of :attr:`solid_node`.

        Notes
        -----
        Where the coupling leaves a fibre a free rigid motion (:meth:`free_motions`) the system
        is singular but consistent (the beams carry no load of their own): the solid's
        displacement is unique, the fibre's only up to that motion. The solution without it is
        returned (``Zᵀ u_B = 0`` added as constraints), and :attr:`held` is False.
        """
        kappa = np.asarray(kappa, dtype=np.float64)
        n_B, n_S = self.K_BB.shape[0], len(self.clamped.fixed)
        if D.shape != (3 * len(kappa), n_B) or M.shape != (3 * len(kappa), n_S):
            raise ValueError(f"MonitorProblem.displacement: D {D.shape}, M {M.shape} do not fit this scene "
                             f"({3 * len(kappa)} LM rows, {n_B} beam DOFs, {n_S} solid DOFs)")
        Z = self.free_motions(D, kappa)
        self.held = Z.shape[1] == 0
        rows = np.flatnonzero(np.repeat(kappa > 0.0, 3))
        Dc = D.tocsr()[rows]
        Mc = M.tocsr()[rows]
        reached = np.unique(Mc.indices)
        monitor = 3 * self.solid_node + np.arange(3)
        dofs = np.union1d(reached[~self.clamped.fixed[reached]], monitor)   # clamped columns: u_S = 0
        F = self.clamped.flexibility(dofs)
        MI = Mc[:, dofs]
        MF = np.asarray(MI @ F)                                     # (m, n_I)
        m, k = len(rows), Z.shape[1]
        A = np.zeros((n_B + m + k, n_B + m + k))
        A[:n_B, :n_B] = self.K_BB
        A[n_B:n_B + m, :n_B] = Dc.toarray()
        A[:n_B, n_B:n_B + m] = A[n_B:n_B + m, :n_B].T
        A[n_B:n_B + m, n_B:n_B + m] = -(MI @ MF.T + np.diag(np.repeat(kappa, 3)[rows] / self.penalty))
        A[n_B + m:, :n_B] = Z.T * np.abs(self.K_BB).max()            # scaled like K_BB
        A[:n_B, n_B + m:] = A[n_B + m:, :n_B].T
        rhs = np.concatenate([self.f_B, MI @ self.clamped.u0[dofs], np.zeros(k)])
        y = np.linalg.solve(A, rhs)
        self.n_solves += 1
        u_B, lam = y[:n_B], y[n_B:n_B + m]
        k = np.searchsorted(dofs, monitor)
        u_S = self.clamped.u0[monitor] + MF[:, k].T @ lam
        return np.concatenate([u_B[6 * self.beam_node: 6 * self.beam_node + 3], u_S])


def monitor_scene(beams, solid, reference, penalty=None):
    """The :class:`~mortar1d3d.scene.Scene` of :class:`MonitorProblem` (coupling as ``reference``)."""
    coupling = {"integration": reference.integration, "n_gauss": int(reference.n_gauss), "lm": reference.lm,
                "enforcement": "penalty"}
    if penalty is not None:
        coupling["penalty"] = float(penalty)
    return Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", **MONITOR_SOLID}},
                 beams=[{"mesh": beams, "model": "torsion_free", "section": dict(MONITOR_BEAM)}],
                 coupling=coupling, dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "body", "value": list(MONITOR_BODY_FORCE)}],
                 analysis={"kinematics": "linear", "solver": "direct"}, name="solution monitor")


def solution_monitor(problem, D, M, kappa):
    """Monitor-point displacement of the linear solve with the coupling operators ``D, M, κ``.

    Parameters
    ----------
    problem : MonitorProblem
        The scene's linear problem (stiffness assembled and factorised once).
    D, M : scipy.sparse matrices, kappa : (n_lm,) array
        The operators of one integration variant on the problem's scene.

    Returns
    -------
    (6,) float64
        Displacement of the monitor beam node and of the solid node nearest to it.
    """
    if not isinstance(problem, MonitorProblem):
        raise TypeError(f"solution_monitor: problem must be a MonitorProblem (see MonitorProblem(beams, solid, "
                        f"reference)), got {type(problem).__name__}")
    return problem.displacement(D, M, kappa)


def monitor_error(u, u_ref):
    """Relative error ``|u − u_ref| / |u_ref|`` of the monitor displacements (Euclidean norms; NaN if ``u`` is)."""
    u, u_ref = np.asarray(u, dtype=np.float64), np.asarray(u_ref, dtype=np.float64)
    return float(np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref))
