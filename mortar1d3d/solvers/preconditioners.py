"""The auxiliary-space preconditioner of the penalty system: AMG on the solid carrying its
beams, exact solves of the beam blocks, robust as the penalty grows."""
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from ._common import check_square, split_dofs
from .amg import VCycle, _block_size, build_amg
from ._products import drop_weak_node_blocks, extend_and_add
from .direct import factorize_spd_block

__all__ = ["AuxiliarySpacePreconditioner", "smooth_prolongation", "harmonic_prolongation", "drop_weak_blocks"]


class AuxiliarySpacePreconditioner:
    """Preconditioner for the penalty system of beams coupled to a solid, robust in ε.

    Parameters
    ----------
    A : (n, n) scipy.sparse matrix, SPD
        ``K + ε Bᵀ κ⁻¹ B`` on the free DOFs.
    solid, beam : (n_s,), (n_b,) array_like of int
        Which free DOFs are solid and which are beam (a partition of ``0..n-1``).
    prolongation : (n_b, n_s) scipy.sparse matrix
        ``P``: beam DOFs that follow a solid displacement, ``D P ≈ M`` (e.g.
        :func:`mortar1d3d.physics.coupling.follow_operator` restricted to the free DOFs).
    near_nullspace : (n_s, k) array_like, optional
        Rigid-body modes of the solid DOFs, for the AMG of the auxiliary matrix.
    block_size : {None, 1, 3}
        AMG aggregation of the auxiliary (solid) matrix, see :func:`build_amg`.
    smoothing : {0, 1, 2, "harmonic"}
        Damped Jacobi steps that move ``prolongation`` towards the beams' response to a solid
        motion before ``E`` is formed (:func:`smooth_prolongation`); 0 takes it as it is;
        ``"harmonic"`` takes that response itself, ``−A_BB⁻¹ A_BS`` (:func:`harmonic_prolongation`,
        ``prolongation`` unused): fewer CG iterations at n = 40 and 66 of ``fibre_cube(n, 1000, 20)``
        with ``theta=0.05`` (16 and 21 against 19 and 27), a costlier set-up (benchmarks/README.md,
        "Where the growth with n comes from").
    drop : float
        After smoothing, entries of ``P`` below ``drop`` times the largest of their row are left out.
    theta : float
        Strength threshold of the AMG of ``A_aux`` (:func:`build_amg`), default :attr:`THETA`.
    filter_entries : bool
        The AMG smooths its prolongation with the strong entries of ``A_aux`` only (:func:`build_amg`).
    sparsify : float
        Build the AMG hierarchy from ``A_aux`` without its off-diagonal node blocks below
        ``sparsify`` of their diagonal blocks (:func:`drop_weak_blocks`, blocks of the AMG's
        ``block_size``); 0 builds it from ``A_aux`` itself. CG and the beam solves always use the
        true ``A``.
    compensation : {"none", "abs", "signed"}
        What the dropped blocks leave on the diagonal (:func:`drop_weak_blocks`); ``"signed"``
        keeps the iterations up to δ = 3e-3, ``"abs"`` and ``"none"`` do not (Notes).
    sparsify_scope : {"hierarchy", "smoother"}
        ``"hierarchy"``: the whole AMG hierarchy is built from the sparsified ``A_aux``;
        ``"smoother"``: the hierarchy (and the finest residual) from ``A_aux``, only the
        finest level's Gauss–Seidel sweeps on the sparsified matrix.
    keep_auxiliary : bool
        Keep ``A_aux`` itself (:attr:`auxiliary`) when the hierarchy is built from the sparsified
        matrix (nothing uses it then; by default its memory is released after the sparsification).

    Attributes
    ----------
    LUMPED : dict
        The settings before the smoothed prolongation (CHANGELOG, 2026-11-27) (``smoothing=0, theta=0, drop=0, filter_entries=False,
        sparsify=0``): the lumped follow operator as it is and AMG on every entry of ``A_aux``. The Lagrange block
        preconditioner (:func:`~mortar1d3d.solvers.saddle.solve_saddle`) still uses them, with
        ``sparsify=SPARSIFY``.
    SPARSIFY : float
        The default δ of ``sparsify``.
    auxiliary : scipy.sparse.csr_matrix, (n_s, n_s), or None
        ``A_aux = Eᵀ A E`` with ``E = [I; P]`` (solid rows, then beam rows), ``P`` the smoothed
        prolongation (:func:`auxiliary_matrix`); None when the hierarchy was built from the
        sparsified matrix and ``keep_auxiliary`` is false.
    auxiliary_nnz : int
        Stored entries of ``A_aux`` (also when it is not kept).
    prolongation : (n_b, n_s) scipy.sparse.csr_matrix
        That ``P``.
    sparse_auxiliary : scipy.sparse.bsr_matrix or None
        ``A_aux`` without its weak blocks, the matrix the hierarchy is built from (``sparsify > 0``),
        else None.
    A_bs, A_sb : scipy.sparse.csr_matrix, (n_b, n_s) and (n_s, n_b)
        The coupling blocks of ``A`` (all an application multiplies with besides the V-cycle and the
        beam solves).
    amg : pyamg.multilevel.MultilevelSolver
        Hierarchy of ``A_aux``.
    setup_time : float
        Seconds to build all of the above and factorise the beam block.
    timings : dict of str to float
        Wall seconds of the parts: set-up (``"prolongation smoothing"``, ``"auxiliary matrix"``,
        ``"amg set-up"``, ``"beam factorisation"``) and, summed over the calls of :meth:`matvec` so far,
        ``"applications"``, of which ``"amg cycles"`` (with the products that restrict the
        residual) and ``"beam solves"``.

    Notes
    -----
    With a large penalty ε the low-energy motions of ``A`` are those where the beams follow the
    solid, ``D d_B ≈ M d_S``: a coupled mode of solid and beam DOFs that smoothed aggregation
    on ``A`` (aggregates of nearby DOFs, rigid-body modes as near null space) cannot represent,
    so CG needed 600-800 iterations at ε = 1e3 E. Here the space is split as
    ``[d_S; d_B] = E d_S + [0; d_B − P d_S]``:

    - the *auxiliary space* ``range(E)``: solid motions with the beams following. Its matrix
      ``A_aux = K_SS + Pᵀ K_BB P + ε (M − D P)ᵀ κ⁻¹ (M − D P)`` is the solid stiffened by the
      beams it carries, an elasticity-like matrix with the solid's rigid-body modes, solved by
      one AMG V-cycle;
    - the *beam space* ``[0; y]``: ``A_BB = K_BB + ε Dᵀκ⁻¹D``, block-diagonal per beam, factorised
      exactly (banded Cholesky when the beams' DOFs are numbered along them,
      :func:`~mortar1d3d.solvers.direct.factorize_spd_block`).

    ``A_aux`` connects solid nodes further apart than ``K_SS`` does (``Pᵀ K_BB P`` ties the
    elements a beam element crosses): on ``fibre_cube(n, 1000, 20)`` it has 2.5x (n = 20) and
    2.3x (n = 40) the entries of the solid alone, which makes its V-cycle and set-up costlier than
    the solid's. The extra entries are weak (median 1e-6 of ``√(a_ii a_jj)``, 2 % of the Frobenius
    norm at n = 20), but neither leaving them out of the aggregation (strength threshold θ = 0.02:
    20 -> 17 CG iterations at n = 20, 33 -> 32 at n = 40 with a denser coarse level and 40 % more
    set-up) nor out of the matrix (kept SPD by adding their absolute row sums to the diagonal:
    37-40 iterations at n = 20) paid off with the lumped ``P`` (``LUMPED``).

    **The sparsified hierarchy** (the default since 2026-11-27, session twelve). The AMG is built
    from ``A_aux`` without the node blocks ``A_IJ`` below ``δ = 3e-3`` of ``√(‖A_II‖ ‖A_JJ‖)``
    (Frobenius norms), their row sums (symmetric part) added to the diagonal blocks, so that a
    translation of the nodes is charged nearly what ``A_aux`` charges it
    (:func:`drop_weak_blocks`, ``compensation="signed"``); CG runs on the true ``A``, and the
    sweep's beam solves and products with ``A_SB``, ``A_BS`` are unchanged. On
    ``fibre_cube(n, 1000, 20)`` the finest level goes from 223 to 77 entries per row (n = 20) and
    from 192 to 88 (n = 40; the solid alone: 73 and 77) with the same 12 and 19 CG iterations
    (benchmarks/README.md, "A sparsified hierarchy"). Adding the absolute row sums instead (an SPD
    matrix above ``A_aux``, what was tried with ``LUMPED``) costs iterations (14 at δ = 1e-4, 23 at
    1e-3, 36 at 1e-2, n = 20), and so does leaving them out (``"none"``: 12 at 1e-4, 16 at 3e-3);
    smoothing only the finest
    level on the sparse matrix (``sparsify_scope="smoother"``) keeps the iterations but not the
    set-up's Galerkin product on the full matrix, and saved nothing at n = 20. ``A_aux`` is formed
    by one sparse product (:func:`auxiliary_matrix`) and released once its sparsified form exists
    (``keep_auxiliary``), since neither the V-cycle nor CG uses it.

    **The smoothed prolongation** (the default since 2026-11-27). ``A_aux − S = eᵀ A_BB e`` with
    ``S`` the solid's Schur complement and ``e = P + A_BB⁻¹ A_BS`` the defect of ``P`` against the
    beams' response to a solid motion: with the lumped follow operator that defect carries the
    penalty, so ``A_aux`` drifts from ``S`` as ε grows (CG on ``S`` with an exact solve of
    ``A_aux``: 8 / 17 / 50 iterations at ε = 1e2 / 1e3 / 1e4 E, n = 20). One damped Jacobi step
    of ``P`` towards ``−A_BB⁻¹ A_BS`` (:func:`smooth_prolongation`, entries below 1e-3 of their
    row's largest dropped) brings the exact-solve count at ε = 1e3 E from 17 to 9 (n = 20) and the
    spectrum of ``A_aux⁻¹ S`` on ``fibre_cube(6, 1000, 20)`` from [0.56, 1] to [0.92, 1]
    (benchmarks/penalty_spectrum.py). The V-cycle then limits: with θ = 0 it still needs 20; with
    θ = 0.02 and the AMG's prolongation smoothed on the strong entries only (``filter_entries``,
    which keeps its coarse level and set-up small) CG on the whole system needs 12 iterations at
    n = 20 (the solid alone 11) and 20 at n = 40 (solid 12; 19 since :func:`largest_eigenvalue`),
    against 20 and 33 with ``LUMPED``
    (benchmarks/README.md, "A smoothed follow operator"). Smoothing costs one product
    ``A_BB P`` and a Lanczos estimate of ``λ_max(D⁻¹ A_BB)`` in the set-up.

    Because ``P`` keeps the gap of ``E d_S`` small, the coupling between the two spaces is of
    the order of the beam stiffness, not of ε. One application is the symmetric multiplicative
    Schwarz sweep beam → auxiliary → beam (symmetric and positive definite, so CG applies).
    Measured on ``fibre_cube(n, 1000, 20)`` at ε = 1e3 E, rtol 1e-8 (benchmarks/penalty_solve.py),
    with ``LUMPED``: 14, 20, 33 CG iterations for n = 10, 20, 40, against 608-783 for AMG on ``A``
    (n = 10, 20).
    The additive variant (both corrections from the same residual) saves one product with ``A``
    per application but needed 16/24 iterations against 14/19 (n = 10/20). At a small penalty
    (ε ~ 10 E) plain AMG is the better choice (medium test problem: 19 against 28 iterations),
    but the auxiliary space stays bounded as ε grows (``LUMPED``: 18 iterations at ε = 1e3 and
    1e4 E where plain AMG needs 103 and 319; on ``fibre_cube(8, 150, 10)`` 16 at 1e3 E and 45 at
    1e4 E, the default 12 and 16).
    """

    #: the settings before the smoothed prolongation (the lumped follow operator as it is, AMG with θ = 0): pass as
    #: ``AuxiliarySpacePreconditioner(..., **AuxiliarySpacePreconditioner.LUMPED)``
    LUMPED = dict(smoothing=0, theta=0.0, drop=0.0, filter_entries=False, sparsify=0.0)
    #: the default δ of ``sparsify`` (the penalty path; the Lagrange block preconditioner with LUMPED)
    SPARSIFY = 3e-3
    #: the default strength threshold of the AMG of ``A_aux`` (0.02 before session sixteen: 19 instead of 18
    #: CG iterations at n = 40 of ``fibre_cube(n, 1000, 20)``, the same 12 and 27 at n = 20 and 66)
    THETA = 0.05

    def __init__(self, A, solid, beam, prolongation, near_nullspace=None, *, block_size=None, smoothing=1,
                 theta=THETA, drop=1e-3, filter_entries=True, sparsify=SPARSIFY, compensation="signed", sparsify_scope="hierarchy",
                 keep_auxiliary=False):
        start = time.perf_counter()
        A = check_square(A, "A")
        n = A.shape[0]
        self.solid, self.beam = split_dofs(n, solid, beam)
        n_s, n_b = len(self.solid), len(self.beam)
        if n_s == 0 or n_b == 0:
            raise ValueError("the auxiliary-space preconditioner needs both solid and beam DOFs; "
                             "use build_amg for a system of one kind")
        if not sp.issparse(prolongation) or prolongation.shape != (n_b, n_s):
            raise ValueError(f"prolongation must be a scipy.sparse matrix of shape ({n_b}, {n_s}) "
                             f"(beam DOFs x solid DOFs), got {getattr(prolongation, 'shape', None)}")
        null = None if near_nullspace is None else np.asarray(near_nullspace, dtype=np.float64)
        if null is not None and null.shape[0] != n_s:
            raise ValueError(f"near_nullspace must have one row per solid DOF ({n_s}), got {null.shape}")
        # the model orders the free DOFs solid first, beams after: slices are views, no gathers
        self._s, self._b = _contiguous(self.solid), _contiguous(self.beam)
        if smoothing not in (0, 1, 2, "harmonic"):
            raise ValueError("smoothing must be 0, 1 or 2 (Jacobi steps on the prolongation) or 'harmonic', "
                             f"got {smoothing!r}")
        self.A = A
        self.shape = A.shape
        # solid DOFs first, then the beams' (what the model gives): the rows of A are [A_SS A_SB] and
        # [A_BS A_BB] as they are, used in place (no copies; the products below read them directly)
        ordered = isinstance(self._s, slice) and isinstance(self._b, slice) and self._s.start == 0 \
            and self._b.start == n_s and A.format == "csr" and A.has_canonical_format
        if ordered:
            solid_rows, beam_rows = _row_block(A, self._s), _row_block(A, self._b)
            A_bb = _column_block(beam_rows, n_s, n)
            self.A_bs = _column_block(beam_rows, 0, n_s)
        else:
            rows = A[self._b].tocsr()                            # rows of the beam DOFs
            A_bb = rows[:, self._b].tocsr()
            self.A_bs = rows[:, self._s].tocsr()
            solid_rows = beam_rows = None
            del rows
        self.A_sb = self.A_bs.T.tocsr()                          # A is symmetric
        t = time.perf_counter()
        self._beam_factor = factorize_spd_block(A_bb)
        factor_time = time.perf_counter() - t
        t = time.perf_counter()
        P = harmonic_prolongation(A_bb, self.A_bs, drop, self._beam_factor) if smoothing == "harmonic" else \
            smooth_prolongation(A_bb, self.A_bs, prolongation.tocsr(), smoothing, drop, beam_rows=beam_rows)
        smoothing_time = time.perf_counter() - t
        self.smoothing = smoothing
        if sparsify > 0 and sparsify_scope not in ("hierarchy", "smoother"):
            raise ValueError(f"sparsify_scope must be 'hierarchy' or 'smoother', got {sparsify_scope!r}")
        if ordered:
            auxiliary = auxiliary_matrix(None, self.A_bs, self.A_sb, A_bb, P, solid_rows=solid_rows,
                                         beam_rows=beam_rows)
        else:
            A_ss = A[self._s][:, self._s]
            auxiliary = auxiliary_matrix(A_ss, self.A_bs, self.A_sb, A_bb, P)
            del A_ss
        del solid_rows, beam_rows
        self.auxiliary_nnz = auxiliary.nnz
        self.prolongation = P
        self.timings = {"prolongation smoothing": smoothing_time,
                        "auxiliary matrix": time.perf_counter() - start - smoothing_time - factor_time}
        t = time.perf_counter()
        hierarchy_matrix = sparse = auxiliary
        if sparsify > 0:
            sparse = drop_weak_blocks(auxiliary, sparsify, compensation, _block_size(n_s, block_size))
            if sparsify_scope == "hierarchy":
                hierarchy_matrix = sparse
                if not keep_auxiliary:          # nothing uses A_aux itself any more: its memory goes now
                    auxiliary = None
        self.auxiliary = auxiliary
        # "local" weighting: the spectral-radius estimate of the default took up to a third of the AMG
        # setup of fibre_cube(40) (CPU 14-18 s against 12.4 s, loaded machine), same 33 CG iterations
        self.amg = build_amg(hierarchy_matrix, null, block_size=block_size, weighting="local",
                             improve_candidates=False, theta=theta,
                             filter_entries=filter_entries)
        if sparse is not hierarchy_matrix:
            _smooth_finest_with(self.amg, sparse)
        self.sparse_auxiliary = sparse if sparsify > 0 else None
        self._cycle = VCycle(self.amg)
        self.timings["amg set-up"] = time.perf_counter() - t
        self.timings["beam factorisation"] = factor_time
        self.timings.update({"applications": 0.0, "amg cycles": 0.0, "beam solves": 0.0})
        self.setup_time = time.perf_counter() - start

    @property
    def levels(self):
        """AMG levels of the auxiliary matrix."""
        return len(self.amg.levels)

    def matvec(self, r):
        """One symmetric sweep: beam block, auxiliary space, beam block.

        With the beam block solved exactly the sweep reduces to ``z = V(r_S − A_SB A_BB⁻¹ r_B)``,
        ``x = [z; A_BB⁻¹ (r_B − A_BS z)]`` (``V`` the V-cycle of ``A_aux``): the beam residual after the
        first solve is zero, so its restriction ``Pᵀ r_B`` drops out, and ``P z`` cancels in the second
        beam correction. Products with ``A_SB`` and ``A_BS`` only; ``P`` enters through ``A_aux``.
        """
        start = time.perf_counter()
        s, b = self._s, self._b
        x = np.empty_like(r)
        r_b = r[b]
        y_b = self._beam_factor.solve(r_b)
        t1 = time.perf_counter()
        z = self._cycle.matvec(r[s] - self.A_sb @ y_b)
        t2 = time.perf_counter()
        x[s] = z
        r_b = r_b - self.A_bs @ z
        t3 = time.perf_counter()
        x[b] = self._beam_factor.solve(r_b)
        end = time.perf_counter()
        self.timings["amg cycles"] += t2 - t1
        self.timings["beam solves"] += (t1 - start) + (end - t3)
        self.timings["applications"] += end - start
        return x


def smooth_prolongation(A_bb, A_bs, P, steps=1, drop=0.0, *, beam_rows=None):
    """``P`` moved ``steps`` damped Jacobi steps towards the harmonic extension ``−A_BB⁻¹ A_BS``.

    Parameters
    ----------
    A_bb, A_bs : scipy.sparse matrices, (n_b, n_b) SPD and (n_b, n_s)
        Beam block and beam-solid block of the penalty system.
    P : (n_b, n_s) scipy.sparse.csr_matrix
        The follow operator to start from.
    steps : int
        Number of steps (0 returns ``P``).
    drop : float
        Entries below ``drop`` times the largest magnitude of their row are left out at the end.
    beam_rows : (n_b, n_s + n_b) scipy.sparse.csr_matrix, optional
        ``[A_BS  A_BB]`` if the caller has it (e.g. the beam rows of ``A``, solid columns first);
        formed here otherwise.

    Returns
    -------
    P : (n_b, n_s) scipy.sparse.csr_matrix
        ``P ← P + ω D⁻¹ (−A_BS − A_BB P)``, ``D = diag(A_BB)``, ``ω = 1 / λ_max(D⁻¹ A_BB)``.

    Notes
    -----
    The best ``P`` for the auxiliary space is the beams' response to a solid motion,
    ``−A_BB⁻¹ A_BS``: with it ``A_aux = Eᵀ A E`` *is* the solid's Schur complement ``S``
    (``A_aux − S = (P + A_BB⁻¹ A_BS)ᵀ A_BB (P + A_BB⁻¹ A_BS)``), but it is dense along each beam.
    Every step here widens each row of ``P`` by one band of ``A_BB`` (one beam node's
    neighbours), as smoothed aggregation smooths its tentative prolongator. ``λ_max`` is
    estimated by 10 Lanczos steps from the vector of ones (:func:`largest_eigenvalue`), so the
    result is deterministic.
    """
    if steps == 0 or A_bb.shape[0] == 0:
        return P
    A_bb = A_bb.tocsr()
    d = A_bb.diagonal()
    scale = 1.0 / np.sqrt(d)
    # λ_max of D^-1/2 A_BB D^-1/2, applied as scalings around A_BB (no scaled copy of A_BB); it has a
    # unit diagonal, so its λ_max is at least 1: a Lanczos start that misses the top of the spectrum
    # (an invariant subspace of the ones vector) cannot make ω blow up
    scaled = spla.LinearOperator(A_bb.shape, matvec=lambda v: scale * (A_bb @ (scale * v.reshape(-1))),
                                 matmat=lambda V: scale[:, None] * (A_bb @ (scale[:, None] * V)), dtype=np.float64)
    rho = max(largest_eigenvalue(scaled), 1.0)
    jacobi = 1.0 / (rho * d)
    # P − J (A_BS + A_BB P) = P − J [A_BS  A_BB] [I; P], J = diag(jacobi): each row accumulated once from
    # the operands as they are, the weak entries dropped as the last step's rows are written
    # (SciPy's product of stacked copies, the difference and the drop wrote matrices of P's size several
    # times, in memory fresh from the operating system: benchmarks/README.md, "The set-up in one pass per
    # product")
    joined = _beam_rows(A_bs, A_bb) if beam_rows is None else beam_rows
    identity = sp.identity(P.shape[0], format="csr")
    for step in range(steps):
        P = extend_and_add(joined, P, -jacobi, identity, P, drop if step == steps - 1 else 0.0)
    return P


def harmonic_prolongation(A_bb, A_bs, drop=0.0, factor=None, chunk=64):
    """The beams' response to a solid motion, ``P = −A_BB⁻¹ A_BS``, dense along each beam.

    Parameters
    ----------
    A_bb, A_bs : scipy.sparse matrices, (n_b, n_b) SPD and (n_b, n_s)
        Beam block (block-diagonal: one block per beam, the connected components of its graph)
        and beam-solid block of the penalty system.
    drop : float
        Entries below ``drop`` times the largest of their row are left out.
    factor : object with ``solve``, optional
        A factorisation of ``A_bb`` (:func:`~mortar1d3d.solvers.direct.factorize_spd_block`);
        made here if not given.
    chunk : int
        Right-hand sides per solve (memory: ``n_b x chunk`` numbers).

    Returns
    -------
    P : (n_b, n_s) scipy.sparse.csr_matrix

    Notes
    -----
    With this ``P`` the auxiliary matrix ``Eᵀ A E`` is the solid's Schur complement ``S`` up to
    the dropped entries (``A_BS + A_BB P = 0``). The columns are renumbered per beam: the ``l``-th
    solid DOF a beam touches is its column ``l``, so one solve of the block-diagonal ``A_BB`` with
    ``chunk`` right-hand sides serves the ``l``-th columns of all beams at once (as many solves as
    the most solid DOFs one beam touches, over ``chunk``). An entry below ``drop`` times its row's
    largest so far is dropped at once (it is below that of the whole row too).
    """
    if factor is None:
        factor = factorize_spd_block(A_bb)
    A_bs = A_bs.tocoo()
    n_b, n_s = A_bs.shape
    _, beam_of = connected_components(A_bb, directed=False)
    key = beam_of[A_bs.row].astype(np.int64) * n_s + A_bs.col
    pairs = np.unique(key)                                  # (beam, solid DOF) pairs, beam by beam
    first = np.searchsorted(pairs // n_s, np.arange(beam_of.max() + 2))   # each beam's first pair
    local = np.searchsorted(pairs, key) - first[beam_of[A_bs.row]]       # column within the beam
    touched = np.diff(first)[beam_of]                       # solid DOFs each beam row's beam touches
    most = int(touched.max(initial=0))                     # solid DOFs of the beam that touches most
    largest = np.zeros(n_b)
    rows, cols, vals = [], [], []
    for j in range(0, most, chunk):
        width = min(chunk, most - j)
        rhs = np.zeros((n_b, width))
        inside = (local >= j) & (local < j + width)
        rhs[A_bs.row[inside], local[inside] - j] = -A_bs.data[inside]
        response = factor.solve(rhs)
        size = np.abs(response, out=rhs)
        np.maximum(largest, size.max(axis=1), out=largest)
        size[j + np.arange(width) >= touched[:, None]] = 0.0     # columns past the beam's own
        r, c = np.nonzero(size >= np.maximum(drop * largest, np.finfo(float).tiny)[:, None])
        rows.append(r), cols.append(pairs[first[beam_of[r]] + j + c] % n_s), vals.append(response[r, c])
    P = sp.csr_matrix((np.concatenate(vals + [np.zeros(0)]),
                       (np.concatenate(rows + [np.zeros(0, np.int64)]), np.concatenate(cols + [np.zeros(0, np.int64)]))),
                      shape=(n_b, n_s))
    return drop_weak_entries(P, drop) if drop > 0 else P


def auxiliary_matrix(A_ss, A_bs, A_sb, A_bb, P, *, solid_rows=None, beam_rows=None):
    """``A_aux = Eᵀ A E = A_SS + A_SB P + Pᵀ (A_BS + A_BB P)`` with ``E = [I; P]`` (CSR, ``n_s x n_s``).

    ``W = [A_BS  A_BB] [I; P]`` first, then each row of ``[A_SS  A_SB] [I; P] + Pᵀ W`` accumulated
    once (:func:`~mortar1d3d.solvers._products.extend_and_add`; ``solid_rows`` and ``beam_rows``, the
    rows ``[A_SS  A_SB]`` and ``[A_BS  A_BB]``, if the caller has them, e.g. the rows of ``A``; ``A_ss``
    is then not used). Summing the three products ``A_SB P``, its transpose and ``Pᵀ A_BB P`` and then
    ``A_SS`` made and merged five matrices of ``A_aux``'s size (36M entries at n = 40 of
    ``fibre_cube(n, 1000, 20)``), which cost more than the products (benchmarks/README.md, "Forming
    A_aux in one product"); one SciPy product of the stacked copies ``[I  Pᵀ  A_SB] [A_SS; W; P]``
    wrote them once more ("The set-up in one pass per product"). Equal to the sum up to round-off
    (the products are summed in another order), so symmetric up to round-off.
    """
    W = extend_and_add(_beam_rows(A_bs, A_bb) if beam_rows is None else beam_rows, P)   # A_BS + A_BB P
    if solid_rows is None:
        solid_rows = sp.hstack([A_ss, A_sb], format="csr")
    return extend_and_add(solid_rows, P, None, P.T.tocsr(), W)


def _beam_rows(A_bs, A_bb):
    """``[A_BS  A_BB]`` (CSR, ``n_b x (n_s + n_b)``; stored zeros kept, so the diagonal of ``A_BB`` is
    stored wherever it is)."""
    joined = sp.hstack([A_bs.tocsr(), A_bb.tocsr()], format="csr")
    joined.sum_duplicates()
    return joined


def _row_block(A, rows):
    """The rows ``rows`` (a slice) of the CSR matrix ``A``, sharing its index and value arrays."""
    first, last = A.indptr[rows.start], A.indptr[rows.stop]
    return sp.csr_matrix((A.data[first:last], A.indices[first:last], A.indptr[rows.start:rows.stop + 1] - first),
                         shape=(rows.stop - rows.start, A.shape[1]))


def _column_block(A, start, stop):
    """The columns ``start:stop`` of the CSR matrix ``A`` with sorted indices (one pass over its entries)."""
    inside = (A.indices >= start) & (A.indices < stop)
    before = np.zeros(A.nnz + 1, A.indptr.dtype)       # entries inside before each position
    np.cumsum(inside, out=before[1:])
    indptr = before[A.indptr]
    return sp.csr_matrix((A.data[inside], A.indices[inside] - A.indices.dtype.type(start), indptr),
                         shape=(A.shape[0], stop - start))


def drop_weak_entries(P, drop):
    """``P`` (CSR) without the entries below ``drop`` times the largest magnitude of their row
    (stored zeros removed); also the PETSc sweep's rule (:mod:`mortar1d3d.distributed.auxiliary`)."""
    size = np.abs(P.data)
    counts = np.diff(P.indptr)
    filled = counts > 0
    largest = np.zeros(P.shape[0])
    if size.size:       # the largest magnitude of every non-empty row (reduceat over their starts)
        largest[filled] = np.maximum.reduceat(size, P.indptr[:-1][filled])
    keep = (size >= drop * np.repeat(largest, counts)) & (size > 0)
    rows = np.repeat(np.arange(P.shape[0]), counts)[keep]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=P.shape[0]))])
    return sp.csr_matrix((P.data[keep], P.indices[keep], indptr), shape=P.shape)


def _smooth_finest_with(ml, matrix):
    """The finest level's pre- and post-smoother of the hierarchy ``ml``: the symmetric block
    Gauss–Seidel sweep of ``matrix`` (same size and blocks, BSR) instead of the level's own matrix."""
    from pyamg.relaxation.relaxation import block_gauss_seidel
    from pyamg.util.utils import get_block_diag
    size = matrix.blocksize[0]
    inverse = get_block_diag(matrix, blocksize=size, inv_flag=True)

    def sweep(A, x, b):
        block_gauss_seidel(matrix, x, b, iterations=1, sweep="symmetric", Dinv=inverse, blocksize=size)
    ml.levels[0].presmoother = ml.levels[0].postsmoother = sweep


def drop_weak_blocks(A, delta, compensation="none", block_size=3):
    """``A`` (symmetric, blocks of ``block_size`` x ``block_size``, e.g. the DOFs of one node) without
    its off-diagonal blocks ``A_IJ`` with ``‖A_IJ‖_F < delta √(‖A_II‖_F ‖A_JJ‖_F)``, as a BSR matrix.

    ``compensation`` says what the dropped blocks leave behind: ``"none"`` nothing; ``"abs"`` the
    absolute row sums of their entries added to the diagonal (each dropped entry ``a_ij`` becomes
    ``|a_ij| (e_i − s e_j)(e_i − s e_j)ᵀ``, ``s`` its sign: the result stays above ``A``, SPD);
    ``"signed"`` the symmetric part of their block row sum ``Σ_J A_IJ`` added to the diagonal block
    ``A_II`` (translations, which every block row sum acts on, keep their energy when those sums are
    symmetric).

    One pass over the entries of ``A`` as CSR (:func:`~mortar1d3d.solvers._products.drop_weak_node_blocks`):
    converting the 36M entries of ``A_aux`` at n = 40 of ``fibre_cube(n, 1000, 20)`` to BSR, sorting
    them and selecting the kept blocks with NumPy took 2.2 of the set-up's 6 CPU seconds under cProfile
    (benchmarks/README.md, "The set-up in one pass per product").
    """
    if compensation not in ("none", "abs", "signed"):
        raise ValueError(f"compensation must be 'none', 'abs' or 'signed', got {compensation!r}")
    if A.shape[0] != A.shape[1] or A.shape[0] % block_size:
        raise ValueError(f"A must be square with a size divisible by {block_size}, got {A.shape}")
    return drop_weak_node_blocks(A, delta, compensation, block_size)


def _contiguous(index):
    """``index`` as a slice when it is a run of consecutive integers, else as it is."""
    if len(index) and index[-1] - index[0] == len(index) - 1 and np.all(np.diff(index) == 1):
        return slice(int(index[0]), int(index[-1]) + 1)
    return index


#: Lanczos steps of :func:`largest_eigenvalue`
LANCZOS_STEPS = 10


def largest_eigenvalue(A, steps=LANCZOS_STEPS):
    """The largest Ritz value of ``steps`` Lanczos steps on the symmetric matrix ``A`` (anything with
    ``shape`` and ``A @ v``: a sparse matrix or a ``LinearOperator``) from the vector of ones
    (deterministic; the exact largest eigenvalue when ``A`` is that small).

    A lower bound of ``λ_max`` that converges fast from below. It replaced ARPACK (tolerance 1e-2),
    whose restarts were slow on the scaled beam block of ``fibre_cube(n, 1000, 20)`` (126,000 DOFs,
    1000 fibres alike, so the top of the spectrum is a tight cluster): the ``"prolongation smoothing"`` of
    :attr:`AuxiliarySpacePreconditioner.timings` at n = 20 went from 3.4-5.4 to 2.2 wall seconds at
    a load of 8, with the same 12 CG iterations (19 instead of 20 at n = 40; benchmarks/README.md,
    "Cheaper set-up and applications").
    """
    n = A.shape[0]
    if n <= steps:
        # the matrix itself, column by column (``A`` may be a sparse matrix or any linear operator,
        # e.g. the distributed product of mortar1d3d's PETSc backend); products with 0 and 1 are exact
        return float(np.linalg.eigvalsh(np.asarray(A @ np.eye(n))).max())
    v = np.full(n, 1.0 / np.sqrt(n))
    previous = np.zeros(n)
    alpha, beta = np.zeros(steps), np.zeros(steps)
    for j in range(steps):
        w = A @ v
        if j:
            w -= beta[j - 1] * previous
        alpha[j] = (w * v).sum()            # NumPy sums: threaded BLAS ddot/dnrm2 calls were most of this
        # function's CPU in the set-up of fibre_cube(20, 1000, 20) (benchmarks/README.md, "The set-up in one pass")
        w -= alpha[j] * v
        beta[j] = np.sqrt((w * w).sum())
        if beta[j] <= 1e-14 * abs(alpha[j]):      # an invariant subspace: its Ritz values are exact
            steps = j + 1
            break
        previous, v = v, w / beta[j]
    T = np.diag(alpha[:steps]) + np.diag(beta[:steps - 1], 1) + np.diag(beta[:steps - 1], -1)
    return float(np.linalg.eigvalsh(T).max())
