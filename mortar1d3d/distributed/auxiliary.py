"""The auxiliary-space preconditioner of the penalty system on PETSc (the distributed form of
:class:`mortar1d3d.solvers.preconditioners.AuxiliarySpacePreconditioner`).

GAMG on the penalty system ``A = K + ε Bᵀ κ⁻¹ B`` cannot represent the low-energy motions where the
beams follow the solid (aggregates of nearby unknowns, rigid-body modes as near null space): it
needs hundreds of CG iterations, and its first Galerkin product fills in along the fibres that
the penalty ties together. As in the serial library, the space is split into

- the *auxiliary space* ``range(E)``, ``E = [I; P]``: solid motions with the beams following
  (``P``: :func:`~mortar1d3d.physics.coupling.follow_operator`, formed here from the distributed
  M and κ). Its matrix ``A_aux = Eᵀ A E`` (``MatPtAP``) is the solid stiffened by the beams it
  carries, an elasticity matrix on the solid nodes, preconditioned by one GAMG V-cycle with the
  solid's rigid-body modes;
- the *beam space*: ``A_bb`` (the beam rows and columns of ``A``), block-diagonal per beam, solved
  exactly by block Jacobi with a sparse LU of each rank's block, the blocks made of whole beams
  (:func:`beam_solve_rows`): a beam the partition cuts is solved by the rank owning most of its
  elements, which gets the beam's other rows from their owners (``MatCreateSubMatrix``).

One application is the symmetric multiplicative sweep beam → auxiliary → beam, symmetric, and
positive definite because the beam solve is exact (a convergent beam smoother suffices:
``λ_max(J⁻¹ A_bb) < 2``). The blocks of each rank's owned beam unknowns
(``-mortar_beam_blocks rank``, the sweep before) are not: a beam cut over three ranks can push
``λ_max(J⁻¹ A_bb)`` past 2 (2.70 on the fibre cube with its beams dealt to three ranks,
benchmarks/distributed_sweep.py), and CG then stops with ``KSP_DIVERGED_INDEFINITE_PC``. PETSc
options: prefix ``mortar_aux_`` for the KSP/GAMG of ``A_aux`` (e.g.
``-mortar_aux_pc_gamg_threshold``) and ``mortar_beam_`` for the beam block (e.g.
``-mortar_beam_pc_type lu -mortar_beam_pc_factor_mat_solver_type mumps``: one parallel LU of the
whole block).

``P`` is smoothed at every set-up as the serial default does
(:func:`~mortar1d3d.solvers.preconditioners.smooth_prolongation`): one damped Jacobi step towards
the beams' response to a solid motion, ``P ← P − ω D⁻¹ (A_BS + A_BB P)`` with ``D = diag(A_BB)``
and ``ω = 1 / λ_max(D⁻¹ A_BB)`` estimated as the serial code does, then the entries below
``1e-3`` of their row's largest dropped, and GAMG of ``A_aux`` with the serial strength threshold
(``-mortar_aux_pc_gamg_threshold 0.02`` unless given). ``-mortar_follow lumped`` takes the lumped
``P`` as it is and GAMG without a threshold (the serial ``AuxiliarySpacePreconditioner.LUMPED``).
"""
import numpy as np
import scipy.sparse as sp

from ..physics.coupling import chord_triplets
from ..solvers.preconditioners import drop_weak_entries, largest_eigenvalue
from .numbering import node_owner
from .petsc import Entries, coo_matrix, petsc

#: the PETSc option choosing the follow operator of the sweep: ``smoothed`` (default) or ``lumped``
FOLLOW_OPTION = "mortar_follow"
#: the serial defaults of :class:`~mortar1d3d.solvers.preconditioners.AuxiliarySpacePreconditioner`
#: for each choice: relative drop of the smoothed P, the GAMG strength threshold of A_aux
FOLLOW_SETTINGS = {"smoothed": {"drop": 1e-3, "threshold": 0.02}, "lumped": None}


#: the PETSc option choosing the blocks of the beam solve: ``beam`` (default: every beam whole in the block
#: of one rank, so block Jacobi solves A_bb exactly) or ``rank`` (each rank's owned beam unknowns, cut
#: beams solved inexactly: the sweep can then be indefinite, docs/distributed.md)
BLOCKS_OPTION = "mortar_beam_blocks"


def beam_of_element(mesh):
    """The beam of every element of ``mesh``: the connected pieces of the mesh (elements joined by
    shared nodes), numbered from 0."""
    import scipy.sparse.csgraph as csgraph
    elements = np.asarray(mesh.elements, dtype=np.int64)
    if len(elements) == 0:
        return np.zeros(0, dtype=np.int64)
    # nodes joined along each element (its first node to every other): the beams are the node graph's components
    first = np.repeat(elements[:, 0], elements.shape[1] - 1)
    graph = sp.coo_matrix((np.ones(len(first)), (first, elements[:, 1:].ravel())), shape=(mesh.n_nodes,) * 2)
    _, component = csgraph.connected_components(graph, directed=False)
    return component[elements[:, 0]]


def whole_beam_part(mesh, element_part, n_parts):
    """The rank of every element of ``mesh`` when each beam (:func:`beam_of_element`) is given whole
    to the rank that owns most of its elements in ``element_part`` (ties: the lowest rank)."""
    element_part = np.asarray(element_part, dtype=np.int64)
    if len(element_part) == 0:
        return element_part.copy()
    beam = beam_of_element(mesh)
    counts = np.zeros((beam.max() + 1, n_parts), dtype=np.int64)
    np.add.at(counts, (beam, element_part), 1)
    return np.argmax(counts, axis=1)[beam]          # argmax: the first of equal counts


def beam_solve_rows(model, part, layout, rank):
    """System rows of the beam unknowns (positions, tangents, rotations) whose beam block ``rank``
    solves: those of the beams :func:`whole_beam_part` gives it, whichever ranks own the rows. ``A_bb``
    couples no two beams, so block Jacobi over these blocks is the exact ``A_bb⁻¹``; a beam that the
    partition keeps on one rank stays with its rows (nothing moves)."""
    n_parts = len(layout.ranges) - 1
    rows = [np.zeros(0, dtype=np.int64)]
    for k, g in enumerate(model.groups):
        solver = whole_beam_part(g.mesh, part.beam_part[k], n_parts)
        for block, table in ((g.dofs, g.mesh.elements), (g.rotations, g.type.rotation_nodes(g.mesh))):
            if block.size == 0:
                continue
            owner = node_owner(table, solver, block.size // block.dofs_per_node)
            rows.append(layout.of_serial[block.start + np.flatnonzero(np.repeat(owner, block.dofs_per_node) == rank)])
    return np.sort(np.concatenate(rows))


def blocks_choice():
    """``beam`` or ``rank``, from the PETSc option ``-mortar_beam_blocks`` (default ``beam``)."""
    value = petsc().Options().getString(BLOCKS_OPTION, "beam")
    if value not in ("beam", "rank"):
        raise ValueError(f"-{BLOCKS_OPTION}: expected beam or rank, got {value!r}")
    return value


def follow_choice():
    """``smoothed`` or ``lumped``, from the PETSc option ``-mortar_follow`` (default ``smoothed``)."""
    value = petsc().Options().getString(FOLLOW_OPTION, "smoothed")
    if value not in FOLLOW_SETTINGS:
        raise ValueError(f"-{FOLLOW_OPTION}: expected smoothed or lumped, got {value!r}")
    return value


def follow_matrix(model, ops, kappa, numbering, layout, part, comm, rotation=None):
    """``E = [I; P]`` as a distributed matrix: rows the system unknowns, columns the solid field
    (the rank-major solid DOFs: each rank's first ``3 n_solid_owned`` system rows).

    ``P`` is the serial follow operator (:func:`~mortar1d3d.physics.coupling.follow_operator`):
    a beam node's position is ``κ⁻¹ (M d_S)`` of its LM node, a Hermite tangent the mean over the
    node's elements of the chord derivative of the positions (``Chord P_pos``, one more product).
    Each rank contributes its owned beam elements' rows of M and chords; PETSc sums entries of rows
    another rank owns. Supports: columns of fixed solid unknowns do not carry the beams (a fixed
    solid unknown maps to itself only), rows of fixed beam unknowns are zero, as the serial ``P``
    restricted to the free unknowns. With clamps (``rotation``: the system's ``T``, the identity
    on the solid) the beam rows are taken to the unknowns' basis, ``Tᵀ E``, as the serial ``P``.

    Parameters
    ----------
    ops : list of DistributedOperators
        Per beam group, this rank's M triplets (rank-major) and the distributed κ.
    kappa : list of (n_lm,) arrays
        Per beam group, κ in the serial LM order (every rank).
    rotation : PETSc.Mat, optional

    Returns
    -------
    E : PETSc.Mat
    """
    PETSc = petsc()
    rank = comm.getRank()
    n = model.n_displacement_dofs
    n_solid = 3 * model.n_solid_nodes
    first = int(layout.ranges[rank])
    n_own = int(layout.ranges[rank + 1]) - first
    own_solid = 3 * numbering.solid.count(rank)
    sizes_rows = (n_own, int(layout.ranges[-1]))
    sizes_cols = (own_solid, n_solid)
    fixed = np.zeros(n, dtype=bool)
    fixed[model.fixed_dofs[model.fixed_dofs < n]] = True
    solid_serial_of_new = np.argsort(numbering.solid.new_of_old)
    # the solid injection: this rank's solid rows map to themselves in the solid field
    rows = [first + np.arange(own_solid)]
    cols = [3 * int(numbering.solid.ranges[rank]) + np.arange(own_solid)]
    vals = [np.ones(own_solid)]
    chord_rows, chord_cols, chord_vals = [], [], []
    for k, g in enumerate(model.groups):
        per_node = g.type.dofs_per_node
        mesh = g.mesh
        lm_serial_of_new = np.argsort(numbering.lm[k].new_of_old)
        rm, cm, vm = ops[k].local.M
        lm = lm_serial_of_new[rm // 3]
        # LM nodes 0..n_nodes-1 are the beam nodes; the others (interior) have no beam node to move
        keep = lm < mesh.n_nodes
        lm, comp, cm, vm = lm[keep], (rm % 3)[keep], cm[keep], vm[keep]
        kap = kappa[k][lm]
        solid_dof = 3 * solid_serial_of_new[cm // 3] + cm % 3
        beam_dof = g.dofs.start + per_node * lm + comp
        # fixed beam rows are zeroed at the end: a tangent's chord reads the positions of fixed nodes too
        keep = (kap > 0) & ~fixed[solid_dof]
        rows.append(layout.of_serial[beam_dof[keep]])
        cols.append(cm[keep])                        # the solid field is the rank-major solid numbering
        vals.append(vm[keep] / kap[keep])
        if mesh.element_type.has_tangents:
            r, c, v = chord_triplets(mesh, np.flatnonzero(part.beam_part[k] == rank))
            for i in range(3):
                chord_rows.append(layout.of_serial[g.dofs.start + per_node * r + 3 + i])
                chord_cols.append(layout.of_serial[g.dofs.start + per_node * c + i])
                chord_vals.append(v)
    E = coo_matrix(comm, np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), sizes_rows, sizes_cols,
                   block_size=3)
    if comm.tompi4py().allreduce(sum(len(r) for r in chord_rows)):
        cat = (lambda parts: np.concatenate(parts) if parts else np.zeros(0))
        chord = coo_matrix(comm, cat(chord_rows).astype(np.int64), cat(chord_cols).astype(np.int64), cat(chord_vals),
                           sizes_rows, sizes_rows)
        tangents = chord.matMult(E)                  # the chord of the solid rows is zero: tangent rows only
        E.axpy(1.0, tangents, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        chord.destroy(), tangents.destroy()
    if rotation is not None:
        physical, E = E, rotation.transposeMatMult(E)
        physical.destroy()
    beam_serial = layout.owned_serial(rank)[own_solid:]
    fixed_beam_rows = first + own_solid + np.flatnonzero((beam_serial < n) & fixed[np.minimum(beam_serial, n - 1)])
    E.zeroRows(fixed_beam_rows.astype(PETSc.IntType), diag=0.0)
    return E


def beam_spectral_radius(A, rows, comm):
    """``λ_max(D⁻¹ A_BB)`` of the free beam unknowns, estimated as the serial
    :func:`~mortar1d3d.solvers.preconditioners.smooth_prolongation` does (the same
    :func:`~mortar1d3d.solvers.preconditioners.largest_eigenvalue`: a few Lanczos steps from the
    vector of ones), so that the smoothed ``P`` is the serial one whatever the ranks: rank 0 runs the
    iteration on vectors of the free beam unknowns in their serial order, every product with ``A``
    is distributed (the other ranks take part in each). ``None`` without free beam unknowns.

    Parameters
    ----------
    A : PETSc.Mat
        The system (supports: identity rows and columns).
    rows : (k,) int
        Rank 0: the system rows of the free beam unknowns, in the serial order; other ranks: none.
    """
    mpi = comm.tompi4py()
    n = mpi.bcast(len(rows) if comm.getRank() == 0 else None, root=0)
    if n == 0:
        return None
    x, y = A.createVecs()
    entries = Entries(x, rows if comm.getRank() == 0 else [])
    diagonal = A.getDiagonal()
    scale = 1.0 / np.sqrt(entries(diagonal))
    diagonal.destroy()

    def product(v):
        """``(D^-½ A_BB D^-½) v`` (collective; ``v`` is read on rank 0 only)."""
        PETSc = petsc()
        x.set(0.0)
        if len(scale):
            entries.values.setArray(scale * v)
        entries.scatter.scatter(entries.values, x, addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.REVERSE)
        A.mult(x, y)
        return scale * entries(y)

    try:
        if comm.getRank() == 0:
            import scipy.sparse.linalg as spla
            try:
                def matvec(v):
                    mpi.bcast(True, root=0)
                    return product(np.ravel(v))
                found = largest_eigenvalue(spla.LinearOperator((n, n), matvec=matvec, dtype=np.float64))
            except Exception as exc:            # every rank raises it, none waits for a product
                found = exc
            mpi.bcast(False, root=0)
            found = mpi.bcast(found, root=0)
        else:
            while mpi.bcast(None, root=0):
                product(None)
            found = mpi.bcast(None, root=0)
    finally:
        x.destroy(), y.destroy(), entries.scatter.destroy(), entries.values.destroy()
    if isinstance(found, Exception):
        raise found
    return max(found, 1.0)          # as the serial code: the scaled block's unit diagonal bounds λ_max below


def smoothed_follow(A, E, beam_rows, rho, drop):
    """``E`` with its beam rows ``P`` moved one damped Jacobi step towards the beams' response to a
    solid motion, ``P − (ρ D)⁻¹ (A_BS + A_BB P)`` (``D``: the diagonal of ``A``'s beam rows, ``ρ``:
    :func:`beam_spectral_radius`), then each row's entries below ``drop`` times its largest left out: the
    serial :func:`~mortar1d3d.solvers.preconditioners.smooth_prolongation` on this rank's rows.
    The solid rows (the identity) are kept; fixed beam rows (zero rows of ``E``, identity rows of
    ``A``) stay zero. Returns a new matrix.
    """
    PETSc = petsc()
    first, last = A.getOwnershipRange()
    local = np.asarray(beam_rows) - first
    n_local, n_solid = last - first, E.getSize()[1]

    def rows_of(M, n_rows):
        indptr, indices, data = M.getValuesCSR()
        return sp.csr_matrix((data, indices, indptr), shape=(n_rows, n_solid))

    # A_BS + A_BB P: the beam rows of A E only (the solid rows of A E, K_SS + A_SB P, are not needed)
    comm = A.getComm()
    columns = A.getOwnershipRangeColumn()
    rows_is = PETSc.IS().createGeneral(np.asarray(beam_rows).astype(PETSc.IntType), comm=comm)
    cols_is = PETSc.IS().createStride(columns[1] - columns[0], first=columns[0], step=1, comm=comm)
    beam_part = A.createSubMatrix(rows_is, cols_is)
    product = beam_part.matMult(E)
    held, moved = rows_of(E, n_local), rows_of(product, len(local))
    product.destroy(), beam_part.destroy(), rows_is.destroy(), cols_is.destroy()
    d = A.getDiagonal()
    jacobi = sp.diags(1.0 / (rho * d.getArray()[local]))
    d.destroy()
    P = (held[local] - jacobi @ moved).tocsr()
    if drop > 0:
        P = drop_weak_entries(P, drop)
    P.eliminate_zeros()
    rows = sp.vstack([held[:local[0] if len(local) else n_local], P], format="csr")
    rows.sort_indices()
    smoothed = PETSc.Mat().create(comm=A.getComm())
    smoothed.setSizes(E.getSizes())
    smoothed.setType(PETSc.Mat.Type.MPIAIJ)           # as A, also on one rank (MatPtAP wants the same type)
    smoothed.setPreallocationCSR((rows.indptr.astype(PETSc.IntType), rows.indices.astype(PETSc.IntType), rows.data))
    smoothed.assemble()
    return smoothed


class AuxiliarySweep:
    """The python context of a ``PCPYTHON``: the symmetric sweep beam → auxiliary space → beam
    (module docstring), set up from the preconditioner's matrix.

    Parameters
    ----------
    follow : PETSc.Mat
        ``E`` (system rows × solid field), in the unknowns' basis, with the lumped ``P``.
    beam_rows : (k,) int
        System rows of this rank's beam unknowns.
    solid_modes : list of (3 n_solid_owned,) arrays
        This rank's entries of the solid's rigid-body modes (near null space of ``A_aux``).
    smoothing : dict, optional
        ``P`` smoothed at every set-up (:func:`smoothed_follow`) with ``drop``, and ``A_aux``'s GAMG
        with the strength ``threshold`` (:data:`FOLLOW_SETTINGS`); None: the lumped ``P``.
    free_beam_rows : (k,) int, optional
        Rank 0: system rows of the free beam unknowns in the serial order (:func:`beam_spectral_radius`).
    solve_rows : (k,) int, optional
        System rows of the beam block this rank solves (:func:`beam_solve_rows`: whole beams, also
        rows other ranks own); default (and with ``-mortar_beam_blocks rank``) ``beam_rows``.
    """

    def __init__(self, follow, beam_rows, solid_modes, smoothing=None, free_beam_rows=(), solve_rows=None):
        self.lumped, self.beam_rows, self.modes = follow, np.asarray(beam_rows), solid_modes
        self.smoothing, self.free_beam_rows = smoothing, np.asarray(free_beam_rows, dtype=np.int64)
        self.solve_rows = self.beam_rows if solve_rows is None else np.asarray(solve_rows, dtype=np.int64)
        self.amg = self.beam = self.A = self.E = None

    def setUp(self, pc):
        from .linear import null_space
        PETSc = petsc()
        self.destroy(pc)
        _, A = pc.getOperators()
        comm = A.getComm()
        self.A = A
        self.E, defaults = self.lumped, {}
        if self.smoothing is not None:
            rho = beam_spectral_radius(A, self.free_beam_rows, comm)
            if rho is not None:
                self.E = smoothed_follow(A, self.lumped, self.beam_rows, rho, self.smoothing["drop"])
            defaults["mortar_aux_pc_gamg_threshold"] = self.smoothing["threshold"]
        aux = A.ptap(self.E)
        aux.setBlockSize(3)
        aux.setNearNullSpace(null_space(self.modes, comm))
        with _defaults(defaults):
            self.amg = _preonly(aux, "mortar_aux_", PETSc.PC.Type.GAMG)
        # the beam block, rows and columns in the order of the ranks' blocks (whole beams: PETSc moves a
        # cut beam's rows that other ranks own to the rank solving it)
        solve_rows = self.solve_rows if blocks_choice() == "beam" else self.beam_rows
        index = PETSc.IS().createGeneral(solve_rows.astype(PETSc.IntType), comm=comm)
        beam = A.createSubMatrix(index, index)
        with _defaults({"mortar_beam_sub_pc_type": "lu"}):      # each rank's block: exact
            self.beam = _preonly(beam, "mortar_beam_", PETSc.PC.Type.BJACOBI)
        self._rb, self._xb = beam.createVecs()
        aux.destroy(), beam.destroy()                   # the KSPs keep their references
        self._r = A.createVecLeft()
        self._s, self._z = self.E.createVecRight(), self.E.createVecRight()
        self._scatter = PETSc.Scatter().create(self._r, index, self._rb, None)
        index.destroy()

    def _beam_solve(self, r, y):
        """``y += A_bb⁻¹ r_b`` (the beam rows of ``r``; block Jacobi over the ranks' blocks: exact with
        whole beams)."""
        PETSc = petsc()
        self._scatter.scatter(r, self._rb, addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        self.beam.solve(self._rb, self._xb)
        self._scatter.scatter(self._xb, y, addv=PETSc.InsertMode.ADD_VALUES, mode=PETSc.ScatterMode.REVERSE)

    def apply(self, pc, r, y):
        y.set(0.0)
        self._beam_solve(r, y)
        res = self._r
        self.A.mult(y, res)
        res.aypx(-1.0, r)                               # r − A y
        self.E.multTranspose(res, self._s)
        self.amg.solve(self._s, self._z)
        self.E.multAdd(self._z, y, y)
        self.A.mult(y, res)
        res.aypx(-1.0, r)
        self._beam_solve(res, y)

    def destroy(self, pc=None):
        if self.E is not None and self.E is not self.lumped:
            self.E.destroy()                            # the smoothed E of the last set-up (the lumped is the caller's)
        self.E = None
        for name in ("amg", "beam", "_rb", "_xb", "_r", "_s", "_z", "_scatter"):
            obj = getattr(self, name, None)
            if obj is not None:
                obj.destroy()
            setattr(self, name, None)
        self.A = None


class _defaults:
    """PETSc options set for a ``with`` block where the user has not given them (the set-up inside
    reads them); PETSc's options are the process's, so ours are removed again afterwards."""

    def __init__(self, values):
        self.values, self.ours = values, []

    def __enter__(self):
        options = petsc().Options()
        self.ours = [k for k in self.values if not options.hasName(k)]
        for key in self.ours:
            options.setValue(key, self.values[key])

    def __exit__(self, *exc):
        for key in self.ours:
            petsc().Options().delValue(key)


def _preonly(A, prefix, pc_type):
    """A set-up KSP that applies the preconditioner ``pc_type`` of ``A`` once (PETSc options: ``prefix``)."""
    PETSc = petsc()
    ksp = PETSc.KSP().create(comm=A.getComm())
    ksp.setOptionsPrefix(prefix)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    ksp.getPC().setType(pc_type)
    ksp.setOperators(A)
    ksp.setFromOptions()
    ksp.setUp()
    return ksp
