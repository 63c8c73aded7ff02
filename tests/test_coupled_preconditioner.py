"""The parts of the auxiliary-space preconditioner that make the coupled solve cheaper: the banded
Cholesky of the beam blocks, on its own and inside the preconditioner on a fibre scene."""
import numpy as np
import pytest
import scipy.sparse as sp

from mortar1d3d.solvers.direct import (BANDED_MAX_BANDWIDTH, BandedCholesky, bandwidth, factorize,
                                       factorize_spd_block)


def banded_blocks(sizes, k, rng, shift=1.0):
    """Block-diagonal symmetric matrix of banded blocks (half-bandwidth k), like the beams of a
    scene one after the other; ``shift`` < 0 makes it indefinite."""
    blocks = []
    for m in sizes:
        B = np.zeros((m, m))
        for d in range(1, k + 1):
            v = rng.standard_normal(m - d)
            B += np.diag(v, d) + np.diag(v, -d)
        B += np.diag(shift * (2 * k + 1 + rng.random(m)))   # diagonally dominant when shift = 1
        blocks.append(sp.csr_matrix(B))
    return sp.block_diag(blocks, format="csr")


def test_banded_cholesky_solves_like_superlu():
    rng = np.random.default_rng(5)
    A = banded_blocks([30, 45, 21, 60], 5, rng)
    assert bandwidth(A) == 5
    b = rng.standard_normal((A.shape[0], 2))
    factor = factorize_spd_block(A)
    assert isinstance(factor, BandedCholesky) and factor.factor.shape == (6, A.shape[0])
    x = factor.solve(b)
    x_lu = factorize(A, symmetric_positive=True).solve(b)
    assert np.abs(A @ x - b).max() <= 1e-12 * np.abs(b).max()
    assert np.abs(x - x_lu).max() <= 1e-12 * np.abs(x_lu).max()
    assert np.array_equal(factor.solve(b[:, 0]), x[:, 0])


def test_wide_or_indefinite_blocks_go_to_superlu():
    rng = np.random.default_rng(6)
    A = banded_blocks([40, 40, 40], 3, rng)
    # the same matrix with its DOFs shuffled: a bandwidth far beyond the banded limit
    perm = rng.permutation(A.shape[0])
    wide = A[perm][:, perm].tocsr()
    assert bandwidth(wide) > BANDED_MAX_BANDWIDTH
    b = rng.standard_normal(A.shape[0])
    factor = factorize_spd_block(wide)
    assert not isinstance(factor, BandedCholesky)
    assert np.abs(wide @ factor.solve(b) - b).max() <= 1e-12 * np.abs(b).max()
    # indefinite (negative diagonal block): the banded Cholesky meets a negative pivot, SuperLU solves it
    mixed = sp.block_diag([A, banded_blocks([20], 3, rng, shift=-1.0)], format="csr")
    with pytest.raises(np.linalg.LinAlgError):
        BandedCholesky(mixed, bandwidth(mixed))
    b = rng.standard_normal(mixed.shape[0])
    factor = factorize_spd_block(mixed)
    assert not isinstance(factor, BandedCholesky)
    assert np.abs(mixed @ factor.solve(b) - b).max() <= 1e-10 * np.abs(b).max()


@pytest.fixture(scope="module")
def fibre_system():
    """fibre_cube(8, 150, 10) in a clamped linear-elastic cube at the default penalty: (A, b, R, split)
    of the reduced system (11,844 unknowns, 1,944 of them solid)."""
    import mortar1d3d as m13
    from mortar1d3d.model import Model
    beams, solid = m13.generate.fibre_cube(8, 150, 10)
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                      dirichlet=[{"on": "solid:x_min"}],
                      load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                      analysis={"kinematics": "linear", "solver": "amg"})
    model = Model(scene).prepare()
    r, K = model.residual(np.zeros(model.n_unknowns), 1.0)
    free = model.free
    return K[free][:, free].tocsr(), -r[free], model.rigid_body_modes()[free], model._follow_split()


def test_auxiliary_space_on_fibres_uses_the_banded_beam_factor_and_agrees_with_direct(fibre_system):
    """Hermite fibres, DOFs numbered along each: the beam block is factorised banded; the
    preconditioner (no candidate improvement of the rigid-body modes) keeps its iterations."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    A, b, R, split = fibre_system
    solid = split["solid"]
    pre = AuxiliarySpacePreconditioner(A, solid, split["beam"], split["prolongation"], R[solid], block_size=3)
    assert isinstance(pre._beam_factor, BandedCholesky) and pre.levels == 2
    assert pre._s == slice(0, len(solid))                        # solid first, beams after: no gathers
    x, info = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
    assert info["method"] == "aux" and info["converged"] and info["residual"] <= 1e-8
    assert info["iterations"] <= 20                             # measured 12 (16 with LUMPED)
    x_direct, _ = solve_linear(A, b, "direct")
    assert np.linalg.norm(x - x_direct) <= 1e-7 * np.linalg.norm(x_direct)
    assert set(pre.timings) == {"prolongation smoothing", "auxiliary matrix", "amg set-up", "beam factorisation", "applications",
                                "amg cycles", "beam solves"}
    # the parts of an application are timed inside it (a bookkeeping check, not a speed claim)
    t = pre.timings
    assert t["applications"] > 0 and t["amg cycles"] + t["beam solves"] <= t["applications"]


def test_schur_complement_is_the_solid_block_of_the_balanced_beams_and_spd(fibre_system):
    """``S x`` is the solid part of ``A`` applied to ``[x; A_BB⁻¹(−A_BS x)]`` (whose beam part is
    zero), and S is symmetric positive definite to round-off."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner
    from mortar1d3d.solvers.schur import SchurComplement
    A, b, R, split = fibre_system
    solid = split["solid"]
    pre = AuxiliarySpacePreconditioner(A, solid, split["beam"], split["prolongation"], R[solid], block_size=3)
    S = SchurComplement(pre)
    rng = np.random.default_rng(11)
    x, y = rng.standard_normal((2, len(solid)))
    whole = S.whole(x, np.zeros(A.shape[0]))
    Aw = A @ whole
    scale = np.abs(A).max() * np.abs(whole).max()
    assert np.abs(Aw[len(solid):]).max() <= 1e-9 * scale                  # the beams are balanced
    assert np.abs(Aw[:len(solid)] - S.matvec(x)).max() <= 1e-9 * scale
    assert abs(y @ S.matvec(x) - x @ S.matvec(y)) <= 1e-10 * abs(x @ S.matvec(x))
    assert x @ S.matvec(x) > 0 and y @ S.matvec(y) > 0
    # the reduced right-hand side: the solid residual of x = 0 with the beams balanced (a load on
    # the beams too: the scene loads the solid only)
    f = rng.standard_normal(A.shape[0]) * np.abs(b).max()
    zero = S.whole(np.zeros(len(solid)), f)
    assert np.abs((A @ zero - f)[len(solid):]).max() <= 1e-9 * np.abs(A).max() * np.abs(zero).max()
    assert np.abs(S.rhs(f) - (f - A @ zero)[:len(solid)]).max() <= 1e-9 * np.abs(f).max()
    assert np.abs(S.rhs(f) - f[:len(solid)]).max() > 1e-3 * np.abs(f).max()


def test_schur_cg_reaches_rtol_with_the_auxiliary_space_iterations(fibre_system):
    """``method="schur"``: the whole system's residual below rtol, the direct solution, and no more
    iterations than the auxiliary-space sweep on the whole system (both measured 16)."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    A, b, R, split = fibre_system
    solid = split["solid"]
    x, info = solve_linear(A, b, "schur", near_nullspace=R, block_size=3, rtol=1e-8, **split)
    assert info["method"] == "schur" and info["converged"] and info["residual"] <= 1e-8
    assert np.linalg.norm(b - A @ x) <= 1e-8 * np.linalg.norm(b)
    assert "fallback" not in info
    x_direct, _ = solve_linear(A, b, "direct")
    assert np.linalg.norm(x - x_direct) <= 1e-7 * np.linalg.norm(x_direct)
    pre = info["preconditioner"]
    assert isinstance(pre, AuxiliarySpacePreconditioner)
    _, aux = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
    assert aux["method"] == "aux" and info["iterations"] <= aux["iterations"] <= 20
    # a reused preconditioner keeps the Schur path when asked for it
    _, again = solve_linear(A, b, "schur", preconditioner=pre, rtol=1e-8)
    assert again["method"] == "schur" and again["iterations"] == info["iterations"]
    assert "note" not in again or "ran instead" not in again["note"]
    # kept from another matrix (as Newton's reuse does): the beams' block changed, so the Schur
    # complement built from the kept one would solve the old system; the solve must still be this one's
    beams = np.zeros(A.shape[0])
    beams[split["beam"]] = 0.3 * A.diagonal()[split["beam"]]
    A2 = (A + sp.diags(beams)).tocsr()
    x2, other = solve_linear(A2, b, "schur", preconditioner=pre, rtol=1e-8)
    assert other["converged"] and np.linalg.norm(b - A2 @ x2) <= 1e-8 * np.linalg.norm(b)
    assert "ran instead" in other["note"]
    x2_direct, _ = solve_linear(A2, b, "direct")
    assert np.linalg.norm(x2 - x2_direct) <= 1e-7 * np.linalg.norm(x2_direct)


@pytest.mark.parametrize("n", [0, 1, 2, 3])
def test_smoothed_prolongation_of_tiny_beam_blocks(n):
    """A beam block of 0-3 free DOFs (ARPACK takes none of them): one step is the dense formula
    P − (ρ D)⁻¹ (A_BS + A_BB P), ρ the largest eigenvalue of D^-½ A_BB D^-½, and 0 rows stay 0 rows."""
    from mortar1d3d.solvers.preconditioners import smooth_prolongation
    A = 2.0 * np.eye(n) - 0.5 * (np.eye(n, k=1) + np.eye(n, k=-1)) + np.diag(np.arange(n, dtype=float))
    A_bs = -0.1 * np.arange(1, 4 * n + 1, dtype=float).reshape(n, 4)
    P = np.ones((n, 4))
    got = smooth_prolongation(sp.csr_matrix(A), sp.csr_matrix(A_bs), sp.csr_matrix(P)).toarray()
    if n == 0:
        assert got.shape == (0, 4)
        return
    d = np.diag(A)
    rho = np.linalg.eigvalsh(A / np.sqrt(np.outer(d, d))).max()
    assert np.allclose(got, P - (A_bs + A @ P) / (rho * d)[:, None], rtol=1e-14, atol=1e-15)


def test_drop_weak_entries_against_its_definition():
    """Entries below ``drop`` times the largest magnitude of their row go (one equal to it stays), and
    so do stored zeros; an empty row and a row of one tiny entry are left as they are; the kept
    entries are the input's, bit for bit."""
    from mortar1d3d.solvers.preconditioners import drop_weak_entries
    data = np.array([4.0, -1e-4, 2e-3, 0.0, -3.0, 3e-3, -2.9e-3, 1e-300])
    indices = np.array([0, 1, 3, 2, 0, 1, 2, 3])
    indptr = np.array([0, 3, 4, 4, 7, 8])       # row 1 a stored zero, row 2 empty
    P = sp.csr_matrix((data, indices, indptr), shape=(5, 4))
    expected = np.zeros((5, 4))
    expected[0, 0], expected[3, 0], expected[3, 1], expected[4, 3] = 4.0, -3.0, 3e-3, 1e-300
    got = drop_weak_entries(P, 1e-3)
    assert got.nnz == 4 and np.array_equal(got.toarray(), expected)


def test_auxiliary_matrix_is_the_galerkin_product():
    """``auxiliary_matrix`` (one sparse product) against ``Eᵀ A E`` formed densely, ``E = [I; P]``."""
    from mortar1d3d.solvers.preconditioners import auxiliary_matrix
    rng = np.random.default_rng(5)
    n_s, n_b = 12, 9
    G = sp.random(n_s + n_b, n_s + n_b, density=0.3, random_state=rng)
    A = (G @ G.T + sp.identity(n_s + n_b)).tocsr()
    P = sp.random(n_b, n_s, density=0.4, random_state=rng, format="csr")
    E = np.vstack([np.eye(n_s), P.toarray()])
    expected = E.T @ A.toarray() @ E
    got = auxiliary_matrix(A[:n_s, :n_s], A[n_s:, :n_s].tocsr(), A[:n_s, n_s:].tocsr(), A[n_s:, n_s:].tocsr(), P)
    assert got.format == "csr" and got.shape == (n_s, n_s)
    assert np.abs(got.toarray() - expected).max() <= 1e-14 * np.abs(expected).max()


def test_auxiliary_matrix_from_the_rows_of_A():
    """With the rows of ``A`` handed in (solid DOFs first, what the preconditioner does for the model's
    numbering), ``auxiliary_matrix`` is ``Eᵀ A E`` as well, and the preconditioner's blocks taken from
    those rows in place are the blocks of ``A``."""
    from mortar1d3d.solvers.preconditioners import _column_block, _row_block, auxiliary_matrix
    rng = np.random.default_rng(6)
    n_s, n_b = 12, 9
    G = sp.random(n_s + n_b, n_s + n_b, density=0.3, random_state=rng)
    A = (G @ G.T + sp.identity(n_s + n_b)).tocsr()
    A.sort_indices()                                       # canonical, as the model's matrices
    A.data[A.indptr[n_s]:A.indptr[n_s + 1]] = 0.0        # a beam row of stored zeros
    P = sp.random(n_b, n_s, density=0.4, random_state=rng, format="csr")
    E = np.vstack([np.eye(n_s), P.toarray()])
    expected = E.T @ A.toarray() @ E
    solid_rows, beam_rows = _row_block(A, slice(0, n_s)), _row_block(A, slice(n_s, n_s + n_b))
    assert np.array_equal(beam_rows.toarray(), A[n_s:].toarray())
    A_bs, A_bb = _column_block(beam_rows, 0, n_s), _column_block(beam_rows, n_s, n_s + n_b)
    assert np.array_equal(A_bs.toarray(), A[n_s:, :n_s].toarray()) and A_bs.has_sorted_indices
    assert np.array_equal(A_bb.toarray(), A[n_s:, n_s:].toarray())
    got = auxiliary_matrix(None, A_bs, A_bs.T.tocsr(), A_bb, P, solid_rows=solid_rows, beam_rows=beam_rows)
    assert np.abs(got.toarray() - expected).max() <= 1e-14 * np.abs(expected).max()


@pytest.mark.parametrize("drop", [0.0, 0.3])
def test_products_in_one_pass_against_their_dense_formula(drop):
    """``extend_and_add``: ``f ⊙ (L₁ [I; R₁]) + L₂ R₂`` row by row, with empty rows, a row whose terms
    cancel exactly (left out, as SciPy's products leave out zeros), and the drop rule of
    ``drop_weak_entries`` applied to each finished row."""
    from mortar1d3d.solvers._products import extend_and_add
    from mortar1d3d.solvers.preconditioners import drop_weak_entries
    rng = np.random.default_rng(7)
    m, k, rows = 6, 5, 8
    L1 = sp.random(rows, m + k, density=0.4, random_state=rng, format="lil")
    L1[2, :] = 0.0                                         # an empty row of the first term
    L1[3, :] = 0.0
    L1[3, 1] = 2.0                                         # row 3: 2 e_1 ...
    L1 = L1.tocsr()
    R1 = sp.random(k, m, density=0.5, random_state=rng, format="csr")
    L2 = sp.random(rows, 4, density=0.5, random_state=rng, format="lil")
    L2[3, :] = 0.0
    L2[3, 0] = -1.0                                        # ... minus R2's row 0, which is 2 e_1
    L2[5, :] = 0.0
    L2 = L2.tocsr()
    R2 = sp.random(4, m, density=0.5, random_state=rng, format="lil")
    R2[0, :] = 0.0
    R2[0, 1] = 2.0
    R2 = R2.tocsr()
    factor = rng.standard_normal(rows)
    factor[3] = 1.0
    first = L1.toarray() @ np.vstack([np.eye(m), R1.toarray()])
    expected = factor[:, None] * first + L2.toarray() @ R2.toarray()
    assert np.all(expected[3] == 0.0)
    got = extend_and_add(L1, R1, factor, L2, R2, drop=drop)
    assert got.shape == (rows, m) and got.indices.dtype == np.int32
    assert np.all(got.data != 0.0) and got.getnnz(axis=1)[3] == 0
    want = drop_weak_entries(sp.csr_matrix(expected), drop) if drop else sp.csr_matrix(expected)
    assert np.array_equal(got.toarray() != 0, want.toarray() != 0)
    assert np.abs(got.toarray() - want.toarray()).max() <= 1e-14 * np.abs(expected).max()
    only_first = extend_and_add(L1, R1)
    assert np.abs(only_first.toarray() - first).max() <= 1e-14 * np.abs(first).max()
    with pytest.raises(ValueError, match="columns"):
        extend_and_add(L1[:, 1:], R1)


def test_smoothed_prolongation_keeps_translations_and_approaches_the_beams_response(fibre_system):
    """One Jacobi step of ``P`` towards ``−A_BB⁻¹ A_BS`` (the beams' response to a solid motion, with
    which ``Eᵀ A E`` would be the Schur complement): a rigid translation, which the lumped operator
    already carries exactly (no gap, no beam strain), stays; the energy of the defect
    ``P x + A_BB⁻¹ A_BS x`` in ``A_BB`` falls for random solid motions; entries below ``drop``
    times the row's largest are left out."""
    from mortar1d3d.solvers.direct import factorize_spd_block
    from mortar1d3d.solvers.preconditioners import smooth_prolongation
    A, b, R, split = fibre_system
    s, bm = split["solid"], split["beam"]
    A_bb, A_bs, P0 = A[bm][:, bm].tocsr(), A[bm][:, s].tocsr(), split["prolongation"]
    P1 = smooth_prolongation(A_bb, A_bs, P0, 1, drop=0.0)
    assert smooth_prolongation(A_bb, A_bs, P0, 0) is P0
    # a translation of the free solid DOFs is rigid wherever the beams do not reach the clamped face
    # (whose DOFs are not among the free ones): there the lumped operator carries it exactly,
    # balanced (no beam strain, no gap), and the step leaves it as it is
    translations = R[s][:, :3]
    force = np.abs(A_bs @ translations + A_bb @ (P0 @ translations)).max(axis=1)
    balanced = force <= 1e-9 * np.abs(A_bb).max()
    assert balanced.mean() >= 0.8
    assert np.abs(P0 @ translations - R[bm][:, :3])[balanced].max() <= 1e-12
    assert np.abs(P1 @ translations - P0 @ translations)[balanced].max() <= 1e-10
    assert np.abs(P1 @ translations - P0 @ translations)[~balanced].max() > 1e-3     # it moves elsewhere
    factor = factorize_spd_block(A_bb)
    x = np.random.default_rng(3).standard_normal((len(s), 4))
    response = factor.solve(-(A_bs @ x))

    def defect(P):
        e = P @ x - response
        return np.einsum("ij,ij->j", e, A_bb @ e) / np.einsum("ij,ij->j", x, (A[s][:, s] @ x))

    assert np.all(defect(P1) < 0.3 * defect(P0))
    dropped = smooth_prolongation(A_bb, A_bs, P0, 1, drop=1e-3)
    assert dropped.nnz < P1.nnz
    largest = np.abs(P1).max(axis=1).toarray().ravel()
    gone = np.abs(P1 - dropped).max(axis=1).toarray().ravel()
    assert np.all(gone < 1e-3 * largest + 1e-300)


@pytest.fixture(scope="module")
def stiff_penalty_system():
    """The scene of ``fibre_system`` at ε = 1e4 E (where the lumped follow operator's gap costs most)."""
    import mortar1d3d as m13
    from mortar1d3d.model import Model
    beams, solid = m13.generate.fibre_cube(8, 150, 10)
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                      dirichlet=[{"on": "solid:x_min"}],
                      load=[{"type": "traction", "on": "solid:x_max", "value": [0, 0, -1e6]}],
                      coupling={"penalty": 1e13},
                      analysis={"kinematics": "linear", "solver": "amg"})
    model = Model(scene).prepare()
    r, K = model.residual(np.zeros(model.n_unknowns), 1.0)
    free = model.free
    return K[free][:, free].tocsr(), -r[free], model.rigid_body_modes()[free], model._follow_split()


@pytest.mark.parametrize("system, smoothed, lumped", [("fibre_system", 13, 16), ("stiff_penalty_system", 18, 45)])
def test_smoothed_auxiliary_space_needs_fewer_iterations_than_the_lumped_one(system, smoothed, lumped, request):
    """The default (one smoothing step, AMG with θ = 0.05 and filtered prolongation smoothing) against
    the settings before (``LUMPED``): measured 12 against 16 iterations at the default ε = 1e3 E,
    16 against 45 at 1e4 E; both reach the direct solution."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    A, b, R, split = request.getfixturevalue(system)
    s = split["solid"]
    x_direct, _ = solve_linear(A, b, "direct")
    counts = []
    for options in ({}, AuxiliarySpacePreconditioner.LUMPED):
        pre = AuxiliarySpacePreconditioner(A, s, split["beam"], split["prolongation"], R[s], block_size=3, **options)
        assert pre.smoothing == options.get("smoothing", 1)
        x, info = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
        assert info["converged"] and np.linalg.norm(b - A @ x) <= 1e-8 * np.linalg.norm(b)
        assert np.linalg.norm(x - x_direct) <= 1e-6 * np.linalg.norm(x_direct)
        counts.append(info["iterations"])
    assert counts[0] <= smoothed < lumped <= counts[1]


def test_largest_eigenvalue_by_lanczos_from_the_ones_vector():
    """A lower bound of λ_max close to it after 10 steps; exact for matrices of at most 10 rows and
    when the ones vector spans an invariant subspace (the recurrence stops early)."""
    from mortar1d3d.solvers.preconditioners import largest_eigenvalue
    spectrum = np.linspace(0.5, 3.0, 400)
    estimate = largest_eigenvalue(sp.diags(spectrum))
    assert estimate <= 3.0 and estimate >= 0.98 * 3.0
    assert largest_eigenvalue(sp.diags(spectrum), steps=40) >= estimate
    small = np.diag([1.0, 4.0, 2.0]) + 0.5 * (np.eye(3, k=1) + np.eye(3, k=-1))
    assert largest_eigenvalue(sp.csr_matrix(small)) == pytest.approx(np.linalg.eigvalsh(small).max(), rel=1e-14)
    # a periodic chain: row sums 0, so the ones vector is an eigenvector (eigenvalue 0);
    # the Ritz value of a one-dimensional Krylov space is that eigenvalue, not λ_max = 4 (a lower bound)
    ring = 2.0 * sp.eye(50) - sp.eye(50, k=1) - sp.eye(50, k=-1) - sp.eye(50, k=49) - sp.eye(50, k=-49)
    assert largest_eigenvalue(ring.tocsr()) == pytest.approx(0.0, abs=1e-12)


def test_application_is_the_symmetric_sweep_beam_aux_beam(fibre_system):
    """The application (two beam solves, products with A_SB and A_BS, one V-cycle) equals the sweep
    written out: beam solve, auxiliary-space correction through E = [I; P], beam solve of the new
    residual, to round-off; and it is symmetric."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner
    A, b, R, split = fibre_system
    s, bm = split["solid"], split["beam"]
    pre = AuxiliarySpacePreconditioner(A, s, bm, split["prolongation"], R[s], block_size=3)
    P = pre.prolongation
    rng = np.random.default_rng(21)
    r, q = rng.standard_normal((2, A.shape[0]))
    x = np.zeros(A.shape[0])
    x[bm] = pre._beam_factor.solve(r[bm])
    residual = r - A @ x
    z = pre._cycle.matvec(residual[s] + P.T @ residual[bm])
    x[s] += z
    x[bm] += P @ z
    x[bm] += pre._beam_factor.solve((r - A @ x)[bm])
    got = pre.matvec(r)
    assert np.abs(got - x).max() <= 1e-9 * np.abs(x).max()
    assert abs(q @ pre.matvec(r) - r @ pre.matvec(q)) <= 1e-10 * abs(r @ got)
    assert r @ got > 0


def _symmetric_block_matrix(rng, nodes, symmetric_blocks):
    """A symmetric matrix of 3x3 blocks on a random pattern, SPD by a dominant diagonal, its
    off-diagonal blocks of sizes spread over six decades (symmetric blocks when asked)."""
    B = np.zeros((3 * nodes, 3 * nodes))
    for i in range(nodes):
        for j in rng.choice(nodes, 5, replace=False):
            if j <= i:
                continue
            block = rng.standard_normal((3, 3)) * 10.0 ** rng.uniform(-6, 0)
            if symmetric_blocks:
                block = block + block.T
            B[3 * i:3 * i + 3, 3 * j:3 * j + 3] = block
            B[3 * j:3 * j + 3, 3 * i:3 * i + 3] = block.T
    B += np.diag(np.abs(B).sum(axis=1) + 1.0)
    return B


def test_drop_weak_blocks_keeps_the_strong_blocks_and_what_its_compensation_promises():
    from mortar1d3d.solvers.preconditioners import drop_weak_blocks
    rng = np.random.default_rng(3)
    dense = _symmetric_block_matrix(rng, 40, symmetric_blocks=False)
    A = sp.csr_matrix(dense)
    blocks = np.linalg.norm(dense.reshape(40, 3, 40, 3), axis=(1, 3))
    ratio = blocks / np.sqrt(np.outer(np.diag(blocks), np.diag(blocks)))
    # δ = 0 keeps every stored block: the matrix itself
    assert np.array_equal(drop_weak_blocks(A, 0.0).toarray(), dense)
    delta = 1e-3
    weak = (ratio < delta) & (blocks > 0)
    assert 0 < weak.sum() < (blocks > 0).sum() - 40
    kept = np.kron(~weak, np.ones((3, 3))).astype(bool)
    for compensation in ("none", "abs", "signed"):
        S = drop_weak_blocks(A, delta, compensation).toarray()
        assert drop_weak_blocks(A, delta, compensation).nnz == 9 * (blocks > 0).sum() - 9 * weak.sum()
        off = ~np.kron(np.eye(40, dtype=bool), np.ones((3, 3), dtype=bool))
        assert np.array_equal(S[off & kept], dense[off & kept]) and not S[off & ~kept].any()
        assert np.array_equal(S, S.T)
    # "none": the diagonal blocks as they were; "abs": above A (S - A is positive semidefinite)
    none = drop_weak_blocks(A, delta, "none").toarray()
    assert np.array_equal(np.diag(none), np.diag(dense))
    gap = drop_weak_blocks(A, delta, "abs").toarray() - dense
    assert np.linalg.eigvalsh(gap).min() >= -1e-14 * np.abs(dense).max()
    assert np.linalg.eigvalsh(gap).max() > 0
    # "signed" with symmetric blocks: every translation is mapped as by A
    dense = _symmetric_block_matrix(rng, 40, symmetric_blocks=True)
    S = drop_weak_blocks(sp.csr_matrix(dense), delta, "signed").toarray()
    translations = np.kron(np.ones((40, 1)), np.eye(3))
    assert np.abs(S @ translations - dense @ translations).max() <= 1e-13 * np.abs(dense).max()
    assert np.abs(drop_weak_blocks(sp.csr_matrix(dense), delta).toarray() @ translations
                  - dense @ translations).max() > 1e-9


@pytest.mark.parametrize("system", ["fibre_system", "stiff_penalty_system"])
def test_hierarchy_of_the_sparsified_auxiliary_matrix(system, request):
    """The AMG built from ``A_aux`` without its blocks below 3e-3 of their diagonal blocks, the
    dropped blocks' symmetric row sums on the diagonal (the default): a finest level with fewer entries, CG on
    the true system reaches the direct solution in the iterations of the full ``A_aux`` (+1); with
    the absolute row sums on the diagonal instead, CG needs more. Measured: finest level 296,892 ->
    124,344 entries, 12 / 12 / 13 iterations (fibre_system); 297,270 -> 138,870, 16 / 16 / 18 (ε = 1e4 E)."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    A, b, R, split = request.getfixturevalue(system)
    s = split["solid"]
    x_direct, _ = solve_linear(A, b, "direct")
    counts, finest = {}, {}
    for name, options in (("full", dict(sparsify=0.0)), ("signed", {}),
                          ("abs", dict(sparsify=3e-3, compensation="abs"))):
        pre = AuxiliarySpacePreconditioner(A, s, split["beam"], split["prolongation"], R[s], block_size=3, **options)
        x, info = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
        assert info["converged"] and np.linalg.norm(b - A @ x) <= 1e-8 * np.linalg.norm(b)
        assert np.linalg.norm(x - x_direct) <= 1e-6 * np.linalg.norm(x_direct)
        counts[name], finest[name] = info["iterations"], pre.amg.levels[0].A.nnz
        assert (pre.sparse_auxiliary is None) == (name == "full")
    assert finest["signed"] == finest["abs"] < finest["full"]
    assert counts["signed"] <= counts["full"] + 1 and counts["abs"] > counts["signed"]


def test_harmonic_prolongation_balances_the_beams_and_makes_the_auxiliary_matrix_the_schur_complement(fibre_system):
    """``harmonic_prolongation`` is ``−A_BB⁻¹ A_BS`` (beam by beam, a few right-hand sides per solve):
    the beams it moves carry no force (``A_BS + A_BB P = 0``), ``Eᵀ A E`` is the Schur complement ``S``,
    the result does not depend on how many right-hand sides a solve takes, and ``drop`` leaves out
    exactly the entries below ``drop`` times their row's largest. The preconditioner built on it
    reaches the direct solution in fewer CG iterations than one Jacobi step with θ = 0.02 (the default
    before session sixteen; with the default θ = 0.05 both take 11 on this scene)."""
    from mortar1d3d.solvers.linear import AuxiliarySpacePreconditioner, solve_linear
    from mortar1d3d.solvers.preconditioners import auxiliary_matrix, harmonic_prolongation
    from mortar1d3d.solvers.schur import SchurComplement
    A, b, R, split = fibre_system
    s, bm = split["solid"], split["beam"]
    A_bb, A_bs = A[bm][:, bm].tocsr(), A[bm][:, s].tocsr()
    P = harmonic_prolongation(A_bb, A_bs)
    assert abs(P - harmonic_prolongation(A_bb, A_bs, chunk=7)).max() <= 1e-14 * abs(P).max()
    assert abs(A_bs + A_bb @ P).max() <= 1e-10 * abs(A_bs).max()
    aux = auxiliary_matrix(A[s][:, s], A_bs, A_bs.T.tocsr(), A_bb, P)
    pre = AuxiliarySpacePreconditioner(A, s, bm, split["prolongation"], R[s], block_size=3)
    x = np.random.default_rng(4).standard_normal(len(s))
    Sx = SchurComplement(pre).matvec(x)
    assert np.abs(aux @ x - Sx).max() <= 1e-9 * np.abs(Sx).max()
    dropped = harmonic_prolongation(A_bb, A_bs, drop=1e-3)
    largest = abs(P).max(axis=1).toarray().ravel()
    kept = dropped.toarray() != 0
    whole = P.toarray()
    assert np.array_equal(kept, np.abs(whole) >= 1e-3 * largest[:, None])
    assert np.abs(dropped.toarray() - whole)[kept].max() <= 1e-14 * largest.max()
    assert dropped.nnz < 0.5 * P.nnz
    x_direct, _ = solve_linear(A, b, "direct")
    counts = []
    for options in (dict(theta=0.02), dict(smoothing="harmonic", theta=0.05), {}):
        pre = AuxiliarySpacePreconditioner(A, s, bm, split["prolongation"], R[s], block_size=3, **options)
        y, info = solve_linear(A, b, preconditioner=pre, rtol=1e-8)
        assert info["converged"] and np.linalg.norm(y - x_direct) <= 1e-6 * np.linalg.norm(x_direct)
        counts.append(info["iterations"])
    assert counts[1] < counts[0] and counts[2] <= counts[0], counts
