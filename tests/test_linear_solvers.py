"""Linear solvers: rigid-body modes, direct vs AMG+CG, saddle point (direct vs block MINRES).

Test matrices are built here (a compact, test-only hex8 elasticity assembly on a structured box,
clamped at x = 0, plus a chain of axial springs along a slanted line coupled through a synthetic
mortar-like ``B = [-M, D]``: ``D = κ_j I`` at beam node j, ``M = κ_j N_l(x_j) I`` with the
trilinear weights of the solid element containing beam node j). The chain has no transverse
stiffness: only the coupling holds it, so ``K`` is singular on beam DOFs.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from mortar1d3d.solvers.linear import (AuxiliarySpacePreconditioner, LinearSolverError, rigid_body_modes,
                                       solve_linear, solve_saddle)
from mortar1d3d.solvers.krylov import _minres
_HEX8_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                          [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)


def hex8_stiffness(h, E=1.0, nu=0.3):
    """24x24 stiffness of an axis-aligned brick with edge lengths h (2x2x2 Gauss)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[np.arange(3), np.arange(3)] += 2 * mu
    C[np.arange(3, 6), np.arange(3, 6)] = mu
    g = 1 / np.sqrt(3)
    Ke = np.zeros((24, 24))
    for xi in np.array(np.meshgrid([-g, g], [-g, g], [-g, g])).reshape(3, -1).T:
        # dN/dxi of the trilinear functions, then dN/dx = dN/dxi * 2/h (brick)
        terms = 1 + _HEX8_CORNERS * xi
        dN = np.empty((8, 3))
        for i in range(3):
            others = [j for j in range(3) if j != i]
            dN[:, i] = _HEX8_CORNERS[:, i] * terms[:, others[0]] * terms[:, others[1]] / 8 * 2 / h[i]
        Bm = np.zeros((6, 24))
        for a in range(8):
            Bm[0, 3 * a], Bm[1, 3 * a + 1], Bm[2, 3 * a + 2] = dN[a]
            Bm[3, 3 * a], Bm[3, 3 * a + 1] = dN[a, 1], dN[a, 0]
            Bm[4, 3 * a + 1], Bm[4, 3 * a + 2] = dN[a, 2], dN[a, 1]
            Bm[5, 3 * a], Bm[5, 3 * a + 2] = dN[a, 2], dN[a, 0]
        Ke += Bm.T @ C @ Bm * np.prod(h) / 8
    return Ke


def box_elasticity(cells, size=(1.0, 1.0, 1.0), E=1.0, nu=0.3):
    """(K, points) of the hex8 elasticity stiffness on a structured box, dof = 3*node + i."""
    nx, ny, nz = cells
    h = np.asarray(size, float) / cells
    grid = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    c = _HEX8_CORNERS.astype(int) > 0
    conn = np.stack([grid[k + ck, j + cj, i + ci] for ci, cj, ck in c], axis=1)
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(len(conn), 24).astype(np.int32)
    Ke = hex8_stiffness(h, E, nu)
    rows = np.repeat(dofs, 24, axis=1).ravel()
    cols = np.tile(dofs, (1, 24)).ravel()
    data = np.broadcast_to(Ke.ravel(), (len(conn), 576)).ravel()
    n = 3 * grid.size
    K = sp.csr_matrix((data, (rows, cols)), shape=(n, n))
    zz, yy, xx = np.meshgrid(*(np.linspace(0, s, m + 1) for s, m in zip(size[::-1], cells[::-1])), indexing="ij")
    points = np.column_stack([xx.ravel(), yy.ravel(), zz.ravel()])
    return K, points


def trilinear_weights(points, cells, size):
    """(element nodes (n, 8), weights (n, 8)) of points in the structured box."""
    nx, ny, nz = cells
    h = np.asarray(size, float) / cells
    idx = np.minimum((points / h).astype(int), np.array(cells) - 1)
    xi = 2 * (points / h - idx) - 1
    grid = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    c = _HEX8_CORNERS.astype(int) > 0
    nodes = np.stack([grid[idx[:, 2] + ck, idx[:, 1] + cj, idx[:, 0] + ci] for ci, cj, ck in c], axis=1)
    weights = np.prod(1 + _HEX8_CORNERS[None] * xi[:, None, :], axis=2) / 8
    return nodes, weights


def coupled_problem(cells, size=(2.0, 1.0, 1.0), n_beam=None, E=1.0, spring=1.0):
    """Elastic box clamped at x = 0 + a chain of axial springs coupled through a synthetic B.

    Returns dict(K (reduced), B (reduced columns), kappa, solid, beam, free, R (free rows), b, points...).
    """
    Ks, P = box_elasticity(cells, size, E=E)
    n_s = Ks.shape[0]
    if n_beam is None:
        n_beam = cells[0] // 2 + 1
    start = np.array([0.13, 0.52, 0.47]) * size
    end = np.array([0.91, 0.44, 0.55]) * size
    X_b = start + np.linspace(0, 1, n_beam)[:, None] * (end - start)
    l = np.linalg.norm(end - start) / (n_beam - 1)
    # beam: axial springs only, singular transversally (held only by the coupling)
    e = (end - start) / np.linalg.norm(end - start)
    ke = spring / l * np.kron(np.array([[1, -1], [-1, 1]]), np.outer(e, e))
    rows, cols, vals = [], [], []
    for k in range(n_beam - 1):
        d = np.r_[3 * k:3 * k + 6]
        rows.append(np.repeat(d, 6)); cols.append(np.tile(d, 6)); vals.append(ke.ravel())
    Kb = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(3 * n_beam, 3 * n_beam))
    kappa = np.full(n_beam + 1, l)
    kappa[[0, n_beam - 1]] = l / 2
    kappa[-1] = 0.0                     # an LM node no pair touched
    nodes, w = trilinear_weights(X_b, cells, size)
    n_lm = n_beam + 1
    Mr, Mc, Mv = [], [], []
    for i in range(3):
        Mr.append(np.repeat(3 * np.arange(n_beam) + i, 8)); Mc.append((3 * nodes + i).ravel())
        Mv.append((w * kappa[:n_beam, None]).ravel())
    M = sp.csr_matrix((np.concatenate(Mv), (np.concatenate(Mr), np.concatenate(Mc))), shape=(3 * n_lm, n_s))
    D = sp.csr_matrix((np.repeat(kappa[:n_beam], 3), (np.arange(3 * n_beam), np.arange(3 * n_beam))),
                      shape=(3 * n_lm, 3 * n_beam))
    K_full = sp.block_diag([Ks, Kb], format="csr")
    B_full = sp.hstack([-M, D], format="csr")
    clamped = np.flatnonzero(P[:, 0] == 0)
    fixed = (3 * clamped[:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(K_full.shape[0]), fixed)
    K = K_full[free][:, free]
    B = B_full[:, free]
    solid = np.flatnonzero(free < n_s)
    beam = np.flatnonzero(free >= n_s)

    R = rigid_body_modes(np.vstack([P, X_b]))[free]
    f = np.zeros(K_full.shape[0])
    loaded = np.flatnonzero(P[:, 0] == size[0])
    f[3 * loaded + 2] = -1.0 / len(loaded)
    f[3 * loaded + 1] = 0.3 / len(loaded)
    f[n_s + 3 * (n_beam - 1) + 0] = 0.5        # pull the beam's end along x
    return dict(K=K, B=B, kappa=kappa, solid=solid, beam=beam, free=free, R=R, b=f[free],
                Ks=Ks, Kb=Kb, M=M, D=D, points=P, beam_points=X_b, n_s=n_s)


def penalty_matrix(prob, epsilon):
    kappa3 = np.repeat(prob["kappa"], 3)
    winv = np.divide(1.0, kappa3, out=np.zeros_like(kappa3), where=kappa3 > 0)
    B = prob["B"]
    return (prob["K"] + epsilon * (B.T @ sp.diags(winv) @ B)).tocsr()


@pytest.fixture(scope="module")
def small():
    """(8, 4, 4) cells: 615 free DOF, 5 beam nodes."""
    return coupled_problem((8, 4, 4))


@pytest.fixture(scope="module")
def medium():
    """(16, 8, 8) cells: 3915 free DOF, 9 beam nodes."""
    return coupled_problem((16, 8, 8))


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


# ----------------------------------------------------------------------------- rigid-body modes

def test_rigid_body_modes_in_null_space_of_free_elasticity():
    K, points = box_elasticity((3, 2, 2), (1.5, 1.0, 1.0))
    R = rigid_body_modes(points + 10.0)       # far from the origin: centring keeps it exact
    assert R.shape == (K.shape[0], 6)
    assert np.abs(K @ R).max() < 1e-12 * abs(K).max()
    assert np.linalg.matrix_rank(R) == 6
    # and they span the whole null space (rank K = n - 6)
    assert np.linalg.matrix_rank(K.toarray(), tol=1e-10) == K.shape[0] - 6


def test_rigid_body_modes_tangents_rotate_only():
    points = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0]])      # a position and a unit tangent
    R = rigid_body_modes(points, tangent_mask=[False, True])
    t = R[3:6]
    assert np.all(t[:, :3] == 0)                                # translations leave tangents alone
    omega = np.eye(3)
    np.testing.assert_allclose(t[:, 3:].T, np.cross(omega, [0.0, 0.0, 1.0]))
    np.testing.assert_allclose(R[0:3, :3], np.eye(3))
    # a rigid motion of the coupled problem's [solid; beam] triplets is tied exactly by B
    prob = coupled_problem((4, 2, 2))
    Bfull = sp.hstack([-prob["M"], prob["D"]])
    Rfull = rigid_body_modes(np.vstack([prob["points"], prob["beam_points"]]))
    assert np.abs(Bfull @ Rfull).max() < 1e-13


def test_rigid_body_modes_about_a_centre_and_scaled():
    """The form Model.rigid_body_modes uses: rotations about the body's centre, divided by its size."""
    points = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0], [4.0, -1.0, 2.0]])
    tangent = np.array([False, True, False])
    centre, size = np.array([0.5, 0.5, 0.5]), 4.0
    R = rigid_body_modes(points, tangent, centre=centre, scale=size)
    arm = np.where(tangent[:, None], points, points - centre) / size
    for k in range(3):
        np.testing.assert_array_equal(R[:, 3 + k].reshape(-1, 3), np.cross(np.eye(3)[k], arm))
        np.testing.assert_array_equal(R[:, k].reshape(-1, 3), np.where(tangent[:, None], 0.0, np.eye(3)[k]))
    # the default centre is the centroid of the positions, the default scale 1
    np.testing.assert_array_equal(rigid_body_modes(points, tangent),
                                  rigid_body_modes(points, tangent, centre=points[~tangent].mean(axis=0)))


def test_linear_module_keeps_every_name_it_exported():
    """solvers.linear was split into one module per idea; what it exported still imports from it."""
    import mortar1d3d.solvers.linear as linear
    from mortar1d3d.solvers import amg, dependent, direct, preconditioners, rigid, saddle
    for module in (amg, dependent, direct, preconditioners, rigid, saddle):
        for name in module.__all__:
            assert getattr(linear, name) is getattr(module, name), name
    assert set(linear.__all__) >= {"LinearSolverError", "rigid_body_modes", "build_amg", "AuxiliarySpacePreconditioner",
                                   "solve_linear", "solve_saddle", "dependent_rows", "DependentRows", "DIRECT_MAX_DOFS",
                                   "SADDLE_DIRECT_MAX_DOFS", "AUGMENTATION_FACTOR", "AUXILIARY_AUGMENTATION_FACTOR"}
    assert linear._factorize is direct.factorize


# ----------------------------------------------------------------------------- SPD systems

def test_direct_and_amg_agree(medium):
    A = penalty_matrix(medium, 20.0)
    x_direct, info_d = solve_linear(A, medium["b"], "direct")
    x_amg, info_a = solve_linear(A, medium["b"], "amg", near_nullspace=medium["R"])
    assert info_d["method"] == "direct" and info_a["method"] == "amg"
    assert info_a["converged"] and info_a["residual"] <= 1e-10
    assert _rel(x_amg, x_direct) < 1e-8
    assert info_a["iterations"] <= 35             # measured 23
    assert info_d["residual"] < 1e-12


def test_near_nullspace_reduces_iterations(medium):
    s = medium["solid"]
    K = medium["K"][s][:, s]
    b = medium["b"][s]
    _, with_modes = solve_linear(K, b, "amg", near_nullspace=medium["R"][s])
    _, without = solve_linear(K, b, "amg")
    assert with_modes["iterations"] <= 20          # measured 13
    assert with_modes["iterations"] * 1.5 < without["iterations"]     # measured 13 vs 27


def test_auto_picks_direct_for_small_systems(small):
    A = penalty_matrix(small, 20.0)
    x, info = solve_linear(A, small["b"])
    assert info["method"] == "direct"
    assert np.linalg.norm(small["b"] - A @ x) <= 1e-12 * np.linalg.norm(small["b"])


def test_amg_warm_start_and_prebuilt_hierarchy(medium):
    from mortar1d3d.solvers.amg import build_amg
    A = penalty_matrix(medium, 20.0)
    ml = build_amg(A, medium["R"])
    x, info = solve_linear(A, medium["b"], preconditioner=ml)
    assert info["method"] == "amg" and info["converged"]
    # a slightly different matrix, the old hierarchy and the old solution as start
    A2 = penalty_matrix(medium, 22.0)
    x2, info2 = solve_linear(A2, medium["b"], preconditioner=ml, x0=x)
    x2_direct, _ = solve_linear(A2, medium["b"], "direct")
    assert _rel(x2, x2_direct) < 1e-8
    assert info2["iterations"] < info["iterations"]


def test_nonconvergence_raises_with_useful_message(medium):
    A = penalty_matrix(medium, 20.0)
    with pytest.raises(LinearSolverError, match=r"relative residual .* after 1 iterations.*Try:.*near_nullspace"):
        solve_linear(A, medium["b"], "amg", maxiter=1)
    with pytest.raises(LinearSolverError, match=r"GMRES did not converge.*after 1 iterations.*penalty_scale"):
        solve_saddle(medium["K"], medium["B"], medium["kappa"], medium["b"], np.zeros(medium["B"].shape[0]),
                     "block", near_nullspace=medium["R"], maxiter=1)


def test_minres_kernel_matches_dense_solve():
    rng = np.random.default_rng(3)
    Q = rng.standard_normal((40, 40))
    A = Q + Q.T                                    # symmetric indefinite
    P = np.diag(np.abs(np.diag(A)) + 1.0)
    b = rng.standard_normal(40)
    x, it, status = _minres(A, b, np.zeros(40), lambda r: r / np.diag(P), 1e-13, 200)
    assert status == "tolerance" and it <= 80      # 40 in exact arithmetic; measured 58
    assert _rel(x, np.linalg.solve(A, b)) < 1e-9


# ----------------------------------------------------------------------------- auxiliary space

def follow_prolongation(prob):
    """P = D⁻¹M for the synthetic coupling (D = κ I at the beam nodes), free rows and columns."""
    n_beam = len(prob["beam_points"])
    kappa3 = np.repeat(prob["kappa"][:n_beam], 3)
    P = sp.diags(1.0 / kappa3) @ prob["M"][:3 * n_beam]
    solid_columns = prob["free"][prob["solid"]]
    beam_rows = prob["free"][prob["beam"]] - prob["n_s"]
    return P.tocsr()[beam_rows][:, solid_columns]


@pytest.mark.parametrize("factor", [1e3, 1e4])
def test_auxiliary_space_robust_at_large_penalty(medium, factor):
    """ε = 1e3 E (the default penalty factor) and 1e4 E: plain AMG degrades, the auxiliary space does not."""
    A = penalty_matrix(medium, factor)                 # E = 1
    P = follow_prolongation(medium)
    x_direct, _ = solve_linear(A, medium["b"], "direct")
    x, info = solve_linear(A, medium["b"], "aux", near_nullspace=medium["R"], solid=medium["solid"],
                           beam=medium["beam"], prolongation=P)
    assert info["method"] == "aux" and info["converged"] and info["residual"] <= 1e-10
    assert _rel(x, x_direct) < 1e-8
    assert info["iterations"] <= 24                    # measured 18 (ε = 1e3) and 18 (ε = 1e4)
    _, plain = solve_linear(A, medium["b"], "amg", near_nullspace=medium["R"], maxiter=2000)
    assert plain["iterations"] >= 4 * info["iterations"]      # measured 103 (ε = 1e3), 319 (ε = 1e4)


@pytest.mark.parametrize("lumped", [True, False])
def test_auxiliary_space_matrix_is_the_galerkin_product(small, lumped):
    """``A_aux = Eᵀ A E`` with ``E = [I; P]``, ``P`` the prolongation as given (``LUMPED``) or after
    the default smoothing step; the sweep is SPD either way."""
    A = penalty_matrix(small, 1e3)
    P = follow_prolongation(small)
    options = AuxiliarySpacePreconditioner.LUMPED if lumped else {"keep_auxiliary": True}
    pre = AuxiliarySpacePreconditioner(A, small["solid"], small["beam"], P, small["R"][small["solid"]], **options)
    assert pre.auxiliary_nnz == pre.auxiliary.nnz
    assert (pre.prolongation is P) if lumped else np.abs(pre.prolongation - P).max() > 1e-3 * np.abs(P).max()
    n = A.shape[0]
    E = sp.lil_matrix((n, len(small["solid"])))
    E[small["solid"], np.arange(len(small["solid"]))] = 1.0
    E[small["beam"]] = pre.prolongation
    E = E.tocsr()
    expected = (E.T @ A @ E).toarray()
    assert np.abs(pre.auxiliary.toarray() - expected).max() <= 1e-12 * np.abs(expected).max()
    if lumped:
        # P = D⁻¹M ties the beam exactly to the solid: the penalty adds nothing to a following motion
        K_aux = (E.T @ small["K"] @ E).toarray()
        assert np.abs(expected - K_aux).max() <= 1e-10 * np.abs(expected).max()
    # the preconditioner is symmetric positive definite (CG needs it)
    rng = np.random.default_rng(0)
    X = rng.standard_normal((n, 6))
    Y = np.column_stack([pre.matvec(v) for v in X.T])
    G = X.T @ Y
    assert np.abs(G - G.T).max() <= 1e-9 * np.abs(G).max()
    assert np.linalg.eigvalsh(0.5 * (G + G.T)).min() > 0


def test_auxiliary_space_argument_errors(small):
    A = penalty_matrix(small, 1e3)
    P = follow_prolongation(small)
    with pytest.raises(ValueError, match="needs solid, beam and prolongation"):
        solve_linear(A, small["b"], "aux")
    with pytest.raises(ValueError, match="prolongation must be .* shape"):
        AuxiliarySpacePreconditioner(A, small["solid"], small["beam"], P.T)
    with pytest.raises(ValueError, match="partition"):
        AuxiliarySpacePreconditioner(A, small["solid"], small["solid"], P)
    # a prebuilt one implies the method, auto picks it above the direct limit only
    pre = AuxiliarySpacePreconditioner(A, small["solid"], small["beam"], P, small["R"][small["solid"]])
    _, info = solve_linear(A, small["b"], preconditioner=pre)
    assert info["method"] == "aux" and info["converged"]
    _, info = solve_linear(A, small["b"], solid=small["solid"], beam=small["beam"], prolongation=P)
    assert info["method"] == "direct"


# ----------------------------------------------------------------------------- saddle points

def _constraint_rhs(prob):
    m = prob["B"].shape[0]
    c = np.zeros(m)
    c[:m - 3] = 1e-3 * np.sin(np.arange(m - 3))    # a prescribed gap; the last LM node has κ = 0
    c[m - 3:] = 7.0                                # ignored: no multiplier there
    return c


@pytest.mark.parametrize("which", ["small", "medium"])
def test_saddle_block_and_direct_agree(which, request):
    prob = request.getfixturevalue(which)
    c = _constraint_rhs(prob)
    args = (prob["K"], prob["B"], prob["kappa"], prob["b"], c)
    kw = dict(solid=prob["solid"], beam=prob["beam"])
    x_d, lam_d, info_d = solve_saddle(*args, "direct", **kw)
    x_b, lam_b, info_b = solve_saddle(*args, "block", near_nullspace=prob["R"], **kw)
    assert info_b["converged"] and info_b["residual"] <= 1e-10
    assert _rel(x_b, x_d) < 1e-8
    assert _rel(lam_b, lam_d) < 1e-8
    rows = slice(0, prob["B"].shape[0] - 3)
    for x in (x_d, x_b):
        gap = prob["B"] @ x - c
        assert np.linalg.norm(gap[rows]) <= 1e-8 * np.linalg.norm(c[rows])
    assert np.all(lam_d[-3:] == 0) and np.all(lam_b[-3:] == 0)
    assert info_b["n_multipliers"] == prob["B"].shape[0] - 3
    # the equilibrium rows: K x + Bᵀ λ = b
    assert np.linalg.norm(prob["K"] @ x_d + prob["B"].T @ lam_d - prob["b"]) <= 1e-10 * np.linalg.norm(prob["b"])


def test_saddle_block_primal_is_the_sparsified_auxiliary_space(medium, monkeypatch):
    """The block solver's primal block with the prolongation: the auxiliary space with the lumped
    follow operator and its AMG built from the sparsified A_aux (as the penalty path); the block
    solve still reaches the direct solution."""
    from mortar1d3d.solvers import saddle
    made = []

    class Recording(saddle.AuxiliarySpacePreconditioner):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(saddle, "AuxiliarySpacePreconditioner", Recording)
    c = _constraint_rhs(medium)
    args = (medium["K"], medium["B"], medium["kappa"], medium["b"], c)
    kw = dict(solid=medium["solid"], beam=medium["beam"])
    x_d, lam_d, _ = solve_saddle(*args, "direct", **kw)
    x_b, lam_b, info = solve_saddle(*args, "block", near_nullspace=medium["R"], prolongation=follow_prolongation(medium),
                                    **kw)
    assert info["converged"] and len(made) == 1
    aux = made[0]
    assert aux.sparse_auxiliary is not None
    # A_aux itself is not kept once the hierarchy has its sparsified form
    assert aux.auxiliary is None
    sparse = sp.csr_matrix(aux.sparse_auxiliary)
    sparse.eliminate_zeros()
    assert sparse.nnz < aux.auxiliary_nnz
    # the finest level of the hierarchy is the sparsified matrix
    assert abs(sp.csr_matrix(aux.amg.levels[0].A) - sparse).max() == 0.0
    assert _rel(x_b, x_d) < 1e-8 and _rel(lam_b, lam_d) < 1e-8


def test_saddle_iterations_bounded_under_refinement():
    counts = []
    for cells in [(12, 6, 6), (24, 12, 12)]:          # 1785 and 12207 free DOF
        prob = coupled_problem(cells)
        x, _, info = solve_saddle(prob["K"], prob["B"], prob["kappa"], prob["b"], _constraint_rhs(prob),
                                  "block", solid=prob["solid"], beam=prob["beam"], near_nullspace=prob["R"])
        assert info["converged"] and info["amg_levels"] >= 2
        counts.append(info["iterations"])
    # measured 38 and 48 (46 at 3915 DOF)
    assert counts[0] <= 50
    assert counts[1] <= 1.5 * counts[0]


def test_saddle_split_primal_agrees(small):
    c = _constraint_rhs(small)
    x_d, lam_d, _ = solve_saddle(small["K"], small["B"], small["kappa"], small["b"], c, "direct")
    x_s, lam_s, info = solve_saddle(small["K"], small["B"], small["kappa"], small["b"], c, "block",
                                    solid=small["solid"], beam=small["beam"], near_nullspace=small["R"],
                                    primal="split")
    assert info["converged"]
    assert _rel(x_s, x_d) < 1e-8 and _rel(lam_s, lam_d) < 1e-8


def test_saddle_singular_raises(small):
    # drop the coupling of the chain: its transverse DOFs are held by nothing
    B = small["B"].tolil()
    B[:, small["beam"]] = 0
    with pytest.raises(LinearSolverError, match="singular"):
        solve_saddle(small["K"], B.tocsr(), small["kappa"], small["b"], np.zeros(B.shape[0]), "direct")


# ----------------------------------------------------------------------------- scenes

def _fibre_scene(solver, n=8, fibres=40, elements=6):
    import mortar1d3d as m13
    beams, solid = m13.generate.fibre_cube(n, fibres, elements)
    return m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                     beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.01}}],
                     dirichlet=[{"on": "solid:x_min"}],
                     load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                     analysis={"kinematics": "linear", "solver": solver})


def test_scene_amg_uses_auxiliary_space_at_default_penalty():
    """Hermite fibres at the default penalty ε = 1e3 E: solver "amg" runs the auxiliary space."""
    import mortar1d3d as m13
    scene = _fibre_scene("amg")
    planned = {e.name for e in m13.plan(scene)}
    assert "linear_solver.follow_operator" in planned
    result = m13.solve(scene)
    info = result.model.last_linear_info
    assert info["method"] == "aux" and info["converged"]
    assert result.model.penalty == 1e3 * 1e9
    assert info["amg_levels"] >= 2
    assert info["iterations"] <= 30                    # measured 22; plain AMG on the same matrix: 306
    assert result.counts["linear_solver.amg"] == 1 and result.counts["linear_solver.follow_operator"] == 1
    assert set(result.counts) <= planned
    direct = m13.solve(_fibre_scene("direct"))
    assert "linear_solver.follow_operator" not in direct.counts
    assert _rel(result.z, direct.z) < 1e-8
    # beams following the solid: P maps a rigid motion of the solid to that of the beams
    from mortar1d3d.physics.coupling import follow_operator
    model = result.model
    g = model.groups[0]
    P = follow_operator(g.operators, g.mesh)
    nS = 3 * model.n_solid_nodes
    R = model.rigid_body_modes()                       # the unit cube: positions scaled by 1
    follow, expected = P @ R[:nS], R[nS:]
    # exact for translations everywhere ...
    np.testing.assert_allclose(follow[:, :3], expected[:, :3], atol=1e-12)
    # ... and for rotations at interior nodes of straight, uniformly divided fibres; at the ends
    # the half-width LM weight shifts the average by a third of an element
    # (positions), and at nodes whose neighbours are interior too (tangents: chord derivatives)
    E = g.mesh.elements
    nodes = np.arange(g.mesh.n_nodes)
    interior = np.isin(nodes, E[:, 0]) & np.isin(nodes, E[:, 1])
    inner = interior.copy()
    inner[E[~interior[E[:, 0]], 1]] = False
    inner[E[~interior[E[:, 1]], 0]] = False
    positions = (6 * np.flatnonzero(interior)[:, None] + np.arange(3)).ravel()
    tangents = (6 * np.flatnonzero(inner)[:, None] + 3 + np.arange(3)).ravel()
    assert len(tangents) == 3 * 40 * 3                 # 40 fibres of 6 elements: 3 such nodes each
    for rows in (positions, tangents):
        np.testing.assert_allclose(follow[rows, 3:], expected[rows, 3:], atol=1e-12)
    assert np.abs(follow[:, 3:] - expected[:, 3:]).max() > 1e-3


def test_amg_setup_is_repeatable_and_leaves_the_callers_random_stream_alone():
    from mortar1d3d.solvers.amg import build_amg
    A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(3000, 3000), format="csr") + 1e-3 * sp.eye(3000)
    np.random.seed(1)
    first = build_amg(A, block_size=1)
    after = np.random.rand()
    np.random.seed(1)
    np.random.rand()                       # another draw in between: pyamg would start elsewhere
    second = build_amg(A, block_size=1)
    for a, b in zip(first.levels, second.levels):
        if hasattr(a, "P"):
            assert (a.P != b.P).nnz == 0
    np.random.seed(1)
    build_amg(A, block_size=1)
    assert np.random.rand() == after       # the caller's stream continues as if nothing happened


@pytest.mark.parametrize("case", ["elasticity", "three levels", "one level", "auxiliary"])
def test_v_cycle_is_pyamgs_preconditioner_bit_for_bit(medium, case):
    """VCycle skips the norms and residual products of pyamg's solve around its one cycle, and
    returns exactly what ``ml.aspreconditioner(cycle="V")`` returns: 2 levels (medium elasticity,
    3x3 blocks), 3 levels (a 1D Laplacian of 3000 rows), 1 level (coarse solve only), and the
    sparsified auxiliary-space hierarchy, whose finest smoother is replaced."""
    from mortar1d3d.solvers.amg import VCycle, build_amg
    if case == "auxiliary":
        A = penalty_matrix(medium, 1e3)
        aux = AuxiliarySpacePreconditioner(A, medium["solid"], medium["beam"], follow_prolongation(medium),
                                           medium["R"][medium["solid"]], block_size=3)
        ml = aux.amg
        assert isinstance(aux._cycle, VCycle)
    elif case == "elasticity":
        ml = build_amg(penalty_matrix(medium, 20.0), medium["R"])
    else:
        A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(3000, 3000), format="csr") + 1e-3 * sp.eye(3000)
        ml = build_amg(A, block_size=1)
        if case == "one level":
            ml.levels = ml.levels[-1:]
    assert len(ml.levels) == {"elasticity": 2, "three levels": 3, "one level": 1, "auxiliary": 2}[case]
    b = np.random.default_rng(5).standard_normal(ml.levels[0].A.shape[0])
    ours, pyamgs = VCycle(ml).matvec(b), ml.aspreconditioner(cycle="V").matvec(b)
    assert np.array_equal(ours, pyamgs) and np.abs(ours).max() > 0
