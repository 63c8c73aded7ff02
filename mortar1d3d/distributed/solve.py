"""A scene on PETSc: distributed assembly, the library's Newton loop or linear step, the result on rank 0.

``solve(scene)`` with ``analysis.backend = "petsc"`` comes here (under ``mpiexec -n N``; one rank
works too). Every rank reads the scene and builds the serial meshes, sets, supports and loads (the
input is replicated in this slice); the work that grows with the model is distributed:

* :func:`~.partition.partition` gives each rank its solid and beam elements;
* each rank assembles its part of D, M and κ (:mod:`.assemble`), and PETSc forms the constant
  coupling matrix from them: the penalty stiffness ε Bᵀ diag(κ)⁻¹ B (B = [−M, D],
  docs/conventions.md §1), or with Lagrange multipliers the saddle block ``[[0, Bᵀ], [B, 0]]`` on
  the coupled LM rows, the multipliers numbered rank by rank after each rank's displacements
  (:class:`SystemLayout`);
* :class:`~.system.DistributedSystem` evaluates the internal forces and tangents of each rank's
  owned solid and beam elements (the serial physics, linear or nonlinear kinematics) into PETSc
  vectors and ``MPIAIJ`` matrices; the library's own
  :func:`~mortar1d3d.solvers.newton.solve_load_steps` (nonlinear: load steps, Newton iterations,
  its convergence tests) or :func:`~mortar1d3d.solvers.newton.solve_linear_step` (linear) runs on
  it, on every rank, with the iterate, residual and increment distributed (each rank its part);
* each linear solve is a PETSc KSP (:mod:`.linear`): for penalty systems CG with the
  auxiliary-space sweep (:mod:`.auxiliary`, the default) or with GAMG and the rigid-body modes,
  MUMPS, or for multipliers a Schur-complement field split.

The solution is gathered on rank 0, which builds the :class:`~mortar1d3d.result.Result` from the
gathered operators (no serial mortar assembly); the other ranks return None.
"""
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..model.checks import check_linear_displacements
from ..physics.coupling import expand3, coupled_nodes, point_projection, point_triplets
from ..scene import SceneError
from .assemble import assemble_distributed
from .numbering import Numbering
from .partition import partition
from .rotational import rotational_parts
from .petsc import coo_matrix, gather_vector, petsc, summed_vector


@dataclass(frozen=True)
class SystemLayout:
    """The system's rank-major numbering: rank r owns ``[its solid node DOFs | its group-0 beam node
    DOFs | group 1 | ... | its rotation nodes' DOFs of the groups with rotations, group by group]``,
    one contiguous range ``ranges[r]:ranges[r + 1]``.

    Attributes
    ----------
    of_serial : (n_displacement,) int64
        System index of every serial displacement unknown (:class:`~mortar1d3d.model.dofmap.DofMap`).
    ranges : (n_parts + 1,) int64
    """

    of_serial: np.ndarray
    ranges: np.ndarray

    @classmethod
    def of(cls, numbering, dofmap, per_node):
        kinds = [(numbering.solid, 3, dofmap.solid)] + [
            (num, p, block) for num, p, block in zip(numbering.beams, per_node, dofmap.centreline)]
        rotations = list(numbering.rotations) + [None] * (len(dofmap.rotations) - len(numbering.rotations))
        for k, (num, block) in enumerate(zip(rotations, dofmap.rotations)):
            if block.size and num is None:
                raise ValueError(f"SystemLayout: beam group {k} has rotations but the numbering has no rotation "
                                 "nodes (Numbering.of(..., beam_types=...))")
            if block.size:
                kinds.append((num, 3, block))
        n_parts = len(numbering.solid.ranges) - 1
        sizes = np.array([[p * num.count(r) for num, p, _ in kinds] for r in range(n_parts)], dtype=np.int64)
        ranges = np.concatenate([[0], np.cumsum(sizes.sum(axis=1))])
        of_serial = np.empty(dofmap.n_displacement, dtype=np.int64)
        for k, (num, p, block) in enumerate(kinds):
            new = num.dofs(np.arange(block.size), p)          # rank-major within the kind
            rank = num.owner[np.arange(block.size) // p]
            start = ranges[rank] + sizes[rank, :k].sum(axis=1) - p * num.ranges[rank]
            of_serial[block.start:block.stop] = start + new
        return cls(of_serial, ranges)

    def with_multipliers(self, owner):
        """The layout of all unknowns: rank r owns its displacement unknowns (as here), then its
        multipliers (``owner``: the rank of each serial multiplier), in their serial order."""
        n_parts = len(self.ranges) - 1
        disp_owner = np.searchsorted(self.ranges, self.of_serial, side="right") - 1
        owner = np.asarray(owner, dtype=np.int64)
        sizes = np.diff(self.ranges) + np.bincount(owner, minlength=n_parts)
        ranges = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        of_serial = np.empty(len(self.of_serial) + len(owner), dtype=np.int64)
        of_serial[:len(self.of_serial)] = self.of_serial - self.ranges[disp_owner] + ranges[disp_owner]
        # after the rank's displacements, in serial order
        per_rank = np.bincount(owner, minlength=n_parts)
        position = np.empty(len(owner), dtype=np.int64)
        position[np.argsort(owner, kind="stable")] = np.arange(len(owner))
        first = np.cumsum(per_rank) - per_rank
        of_serial[len(self.of_serial):] = ranges[owner] + np.diff(self.ranges)[owner] + position - first[owner]
        return SystemLayout(of_serial, ranges)

    def owned_serial(self, rank):
        """Serial index of each unknown ``rank`` owns, in the order of its system range."""
        first, last = self.ranges[rank], self.ranges[rank + 1]
        out = np.empty(last - first, dtype=np.int64)
        mine = (self.of_serial >= first) & (self.of_serial < last)
        out[self.of_serial[mine] - first] = np.flatnonzero(mine)
        return out


def _unsupported(model):
    """SceneError naming the key of the first feature this slice does not distribute."""
    sc = model.scene
    if sc.solid is None:
        return "solid: the PETSc backend needs a solid"
    return None


class _BodyLoads:
    """Stands in for the solid physics while the model folds its dead loads: body loads are kept
    here (and assembled per rank on its owned elements) instead of over the whole mesh."""

    def __init__(self):
        self.values = []

    def body_force(self, b):
        self.values.append(np.asarray(b, dtype=float))
        return 0.0


def _group_operators(model, part, numbering, comm):
    """Each group's distributed D, M, κ, and its κ gathered in the serial LM order (every rank)."""
    c = model.scene.coupling
    options = {k: c[k] for k in ("integration", "n_gauss", "lm", "search_points")}
    ops = [assemble_distributed(model.solid_mesh, g.mesh, part, numbering, group=k, comm=comm, **options)
           for k, g in enumerate(model.groups)]
    kappa = [gather_vector(d.kappa)[num.new_of_old] for d, num in zip(ops, numbering.lm)]
    return ops, kappa


def _constraint_triplets(model, ops, numbering, layout, k):
    """Group ``k``'s B = [−M, D] as (rank-major LM rows of the group, system columns, values), this rank's part."""
    g, dist = model.groups[k], ops[k]
    per_node = g.type.dofs_per_node
    # operator columns (rank-major per kind) back to serial, then to the system
    beam_serial = np.empty(g.dofs.size, dtype=np.int64)
    beam_serial[numbering.beams[k].dofs(np.arange(g.dofs.size), per_node)] = np.arange(g.dofs.size) + g.dofs.start
    solid_serial = np.empty(3 * model.n_solid_nodes, dtype=np.int64)
    solid_serial[numbering.solid.dofs(np.arange(3 * model.n_solid_nodes), 3)] = np.arange(3 * model.n_solid_nodes)
    (rd, cd, vd), (rm, cm, vm) = dist.local.D, dist.local.M
    return (np.concatenate([rd, rm]), layout.of_serial[np.concatenate([beam_serial[cd], solid_serial[cm]])],
            np.concatenate([vd, -vm]))


def _gauss_point_triplets(model, ops, layout, k):
    """Group ``k``'s Gauss-point penalty on this rank's integration points (those of its owned beam
    elements, each point on one rank only): ``ε Gᵀ diag(w) G`` as system triplets, and ``Π G`` (the
    line load before ε κ⁻¹, :meth:`~mortar1d3d.physics.coupling.Coupling.line_load`) as (rank-major
    LM rows, system columns, values). G and Π are the serial ones (:func:`.point_triplets`,
    :func:`.point_projection`) of the rank's local meshes, their columns mapped to the system."""
    g, loc = model.groups[k], ops[k].local
    empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
    if loc.ops is None:
        return empty, empty
    rows, cols, vals = point_triplets(loc.ops, loc.beams, loc.solid)
    n_solid, n_beam = loc.solid.n_nodes, loc.beams.n_centreline_dofs
    per_node = g.type.dofs_per_node
    # G's local scalar columns: the local solid nodes' DOFs, then the local beam mesh's centreline DOFs
    beam = np.arange(n_beam)
    serial = np.concatenate([(3 * loc.solid_nodes[:, None] + np.arange(3)[None, :]).ravel(),
                             g.dofs.start + per_node * loc.beam_nodes[beam // per_node] + beam % per_node])
    system = layout.of_serial[serial]
    G = expand3(sp.csr_matrix((vals, (rows, cols)), shape=(loc.ops.n_integration_points, n_solid + n_beam // 3)))
    K = (model.penalty * (G.T @ sp.diags(np.repeat(loc.ops.point_fields["weight"], 3)) @ G)).tocoo()
    L = (expand3(point_projection(loc.ops, loc.beams)) @ G).tocoo()
    lm_new = loc.kappa[0]
    return ((system[K.row], system[K.col], K.data),
            (3 * lm_new[L.row // 3] + L.row % 3, system[L.col], L.data))


def _penalty_matrix(model, ops, numbering, layout, comm):
    """The penalty stiffness and the line-load operator, formed by PETSc from the ranks' parts.

    Mortar constraint: ε Bᵀ diag(κ)⁻¹ B from the distributed B (rows: per rank, its LM rows of group 0,
    then of group 1, ...) and the summed κ per row. Gauss-point constraint: ε Σ_g w_g G_gᵀ G_g summed
    from the ranks' points (:func:`_gauss_point_triplets`), and Π G in the place of B.

    Returns
    -------
    C : PETSc.Mat
    WB : PETSc.Mat
        ε diag(κ)⁻¹ B, or ε diag(κ)⁻¹ Π G (zero rows where no LM node is coupled): ``WB x`` is the
        line load λ.
    lm_rows : list of (3 n_lm,) int64
        Per group, the row of ``WB`` of every serial LM row.
    """
    rank, n_parts = comm.getRank(), comm.getSize()
    counts = np.array([[3 * num.count(r) for num in numbering.lm] for r in range(n_parts)], dtype=np.int64)
    row_ranges = np.concatenate([[0], np.cumsum(counts.sum(axis=1))])
    gauss_point = model.scene.coupling["constraint"] == "gauss_point"
    rows, cols, vals, k_idx, k_val, lm_rows, stiffness = [], [], [], [], [], [], []
    for k, num in enumerate(numbering.lm):
        def row_of(new_rows):
            # the rank that owns a rank-major LM node: the range it falls in
            lm_rank = np.searchsorted(num.ranges, new_rows // 3, side="right") - 1
            return row_ranges[lm_rank] + counts[lm_rank, :k].sum(axis=1) + new_rows - 3 * num.ranges[lm_rank]

        if gauss_point:
            K, (r, c, v) = _gauss_point_triplets(model, ops, layout, k)
            stiffness.append(K)
        else:
            r, c, v = _constraint_triplets(model, ops, numbering, layout, k)
        rows.append(row_of(r)), cols.append(c), vals.append(v)
        lm_rows.append(row_of(num.dofs(np.arange(3 * num.n), 3)))
        lm_new, kappa = ops[k].local.kappa
        k_idx.append(row_of((3 * lm_new[:, None] + np.arange(3)[None, :]).ravel())), k_val.append(np.repeat(kappa, 3))
    n_rows, local_rows = int(row_ranges[-1]), int(row_ranges[rank + 1] - row_ranges[rank])
    n_sys, local_sys = int(layout.ranges[-1]), int(layout.ranges[rank + 1] - layout.ranges[rank])
    B = coo_matrix(comm, np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), (local_rows, n_rows),
                   (local_sys, n_sys))
    w = summed_vector(comm, np.concatenate(k_idx), np.concatenate(k_val), (local_rows, n_rows))
    arr = w.getArray()
    # the serial rule (physics.coupling.coupled_nodes): coupled rows get ε/κ_j, the others nothing
    coupled = coupled_nodes(arr, model.scene.coupling.get("negative_kappa", "drop"))
    arr = np.where(coupled, model.penalty / np.where(coupled, arr, 1.0), 0.0)
    w.setArray(arr)
    WB = B.copy()
    WB.diagonalScale(L=w)
    if gauss_point:
        sizes = (local_sys, n_sys)
        C = coo_matrix(comm, *(np.concatenate(part) for part in zip(*stiffness)), sizes, sizes)
    else:
        C = B.transposeMatMult(WB)
    B.destroy()
    return C, WB, lm_rows


def _multipliers(model, numbering, kappa):
    """The multipliers in the serial order (group by group, the coupled LM rows κ > 0): per group the
    map from its rank-major LM rows to the multiplier's serial index (−1: not coupled), and the owner
    rank of every multiplier (its LM node's)."""
    maps, owners, start = [], [], 0
    for num, kap in zip(numbering.lm, kappa):
        coupled = np.flatnonzero(np.repeat(coupled_nodes(kap), 3))   # serial LM rows (multipliers: κ > 0)
        serial_row = np.full(3 * num.n, -1, dtype=np.int64)
        serial_row[coupled] = start + np.arange(len(coupled))
        maps.append(serial_row[num.dofs(np.arange(3 * num.n), 3).argsort()])     # rank-major row -> multiplier
        owners.append(num.owner[coupled // 3])
        start += len(coupled)
    return maps, (np.concatenate(owners) if owners else np.zeros(0, np.int64))


def _saddle_matrix(model, ops, numbering, layout, maps, comm):
    """``[[0, Bᵀ], [B, 0]]`` on the coupled rows of B, in the system numbering of all unknowns."""
    n = model.n_displacement_dofs
    rows, cols, vals = [], [], []
    for k, row_map in enumerate(maps):
        r, c, v = _constraint_triplets(model, ops, numbering, layout, k)
        mult = row_map[r]
        keep = mult >= 0
        r = layout.of_serial[n + mult[keep]]
        rows += [r, c[keep]]
        cols += [c[keep], r]
        vals += [v[keep], v[keep]]
    rank = comm.getRank()
    sizes = (int(layout.ranges[rank + 1] - layout.ranges[rank]), int(layout.ranges[-1]))
    return coo_matrix(comm, np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), sizes, sizes)


def _memory_mib():
    """This process's peak and current resident memory in MiB (current: None where /proc is missing)."""
    import resource
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    try:
        with open("/proc/self/statm") as f:
            current = int(f.read().split()[1]) * resource.getpagesize() / 2.0 ** 20
    except OSError:
        current = None
    return peak, current


class _Clock:
    """Per stage: the wall time of the slowest rank (a barrier before each reading), this rank's
    CPU time up to the barrier (its own work; on a loaded machine the fairer measure of balance),
    and its peak and current resident memory at the stage's end (MiB)."""

    def __init__(self, comm):
        self.comm, self.times, self.cpu, self.memory = comm, {}, {}, {}
        self.last, self.last_cpu = time.perf_counter(), time.process_time()

    def __call__(self, stage):
        now_cpu = time.process_time()
        self.cpu[stage] = now_cpu - self.last_cpu
        self.memory[stage] = _memory_mib()
        self.comm.barrier()
        now = time.perf_counter()
        self.times[stage] = now - self.last
        self.last, self.last_cpu = now, time.process_time()


def _traffic(A, comm):
    """What one product with the assembled system moves between ranks, and what each rank stores:
    ``ghosts`` (vector entries each rank receives: the distinct off-rank columns of its rows),
    ``nnz`` (stored entries per rank)."""
    indptr, indices, _ = A.getValuesCSR()
    first, last = A.getOwnershipRange()
    off = np.unique(indices[(indices < first) | (indices >= last)])
    return {"ghosts": comm.tompi4py().allgather(int(len(off))), "nnz": comm.tompi4py().allgather(int(len(indices)))}


#: the PETSc option that selects the preconditioner of penalty systems with beams coupled to a
#: solid: ``aux`` (default: the auxiliary-space sweep, :mod:`.auxiliary`) or ``gamg`` (GAMG on the
#: whole system, the path before it)
PENALTY_PC_OPTION = "mortar_penalty_pc"


def penalty_preconditioner():
    """``aux`` or ``gamg``, from the PETSc option ``-mortar_penalty_pc`` (default ``aux``)."""
    value = petsc().Options().getString(PENALTY_PC_OPTION, "aux")
    if value not in ("aux", "gamg"):
        raise ValueError(f"-{PENALTY_PC_OPTION}: expected aux or gamg, got {value!r}")
    return value


#: the PETSc option that keeps the preconditioner of penalty systems across a Newton loop's solves
#: (:class:`.linear.LinearSolver`, ``reuse``; the default): ``-mortar_reuse_pc 0`` sets one up for
#: every solve
REUSE_PC_OPTION = "mortar_reuse_pc"


def reuse_preconditioner():
    """The PETSc option ``-mortar_reuse_pc`` (default: true)."""
    return petsc().Options().getBool(REUSE_PC_OPTION, True)


def _linear_solver(model, layout, comm, coupling=None, kappa=None):
    """The KSP configuration of ``analysis.solver`` (:mod:`.linear`): penalty systems CG with the
    auxiliary-space sweep (:mod:`.auxiliary`; GAMG on the whole system with ``-mortar_penalty_pc
    gamg`` or without a solid carrying beams), or MUMPS for ``"direct"``; Lagrange multipliers MUMPS for ``"direct"`` and ``"auto"`` (the fallback
    for small cases), the Schur field split for ``"block"`` (``coupling``: the saddle block,
    ``kappa``: κ of every multiplier's LM node, serial order)."""
    from .linear import LinearSolver
    rank = comm.getRank()
    solver = model.scene.analysis["solver"]
    if solver == "direct" or ((model.lagrange or model.rotational_lagrange) and solver == "auto"):
        # (rotational multipliers: MUMPS only, as the serial model takes its direct solver only)
        return LinearSolver("mumps")
    n = model.n_displacement_dofs
    owned = layout.owned_serial(rank)
    R = model.rigid_body_modes()                              # serial numbering, (n, 6)
    disp = owned < n
    modes = [R[owned[disp], j] for j in range(R.shape[1])]
    if not model.lagrange:
        # follower loads and beams with rotations (or 4C's beam3eb) make the tangent of a nonlinear
        # analysis non-symmetric: GMRES instead of CG
        rot = model.scene.coupling.get("rotational") if model.scene.coupled else None
        symmetric = not (model.pressures or model.moments) and (
            model.linear or all(g.type.symmetric_tangent for g in model.groups)) and (
            rot is None or (model.linear and rot["forces"] == "variational"))
        if penalty_preconditioner() == "aux" and model.scene.coupled and model.groups and model.solid_mesh is not None:
            # the beams' unknowns follow each rank's solid ones in its range
            from .auxiliary import FOLLOW_SETTINGS, follow_choice
            own_solid = int(np.count_nonzero(owned < 3 * model.n_solid_nodes))
            # rank 0 estimates the smoothing's weight on the free beam unknowns in the serial order
            free_beam = np.zeros(0, np.int64)
            if rank == 0:
                free_beam = np.setdiff1d(np.arange(3 * model.n_solid_nodes, n), model.fixed_dofs)
            return LinearSolver("aux", symmetric=symmetric, reuse=reuse_preconditioner(), auxiliary={
                "beam_rows": int(layout.ranges[rank]) + np.arange(own_solid, len(owned)),
                "solid_modes": [m[:own_solid] for m in modes], "follow": None,
                "smoothing": FOLLOW_SETTINGS[follow_choice()], "free_beam_rows": layout.of_serial[free_beam]})
        return LinearSolver("gamg", near_null_space=modes, symmetric=symmetric, reuse=reuse_preconditioner())
    PETSc = petsc()
    first = int(layout.ranges[rank])
    gamma = model.scene.solid["material"]["E"]
    # T − I = [[0, Bᵀ W], [0, 0]]: the saddle block's multiplier columns scaled by W = γ / κ
    w = np.zeros(len(owned))
    w[~disp] = gamma / kappa[owned[~disp] - n]
    U = coupling.copy()
    scale = coupling.createVecRight()
    scale.setArray(w)
    U.diagonalScale(R=scale)
    fixed = layout.of_serial[model.fixed_dofs]
    U.zeroRows(fixed[(fixed >= first) & (fixed < first + len(owned))].astype(PETSc.IntType), diag=0.0)
    # −W⁻¹ on the multiplier field (numbered in the field: rank by rank)
    n_mult = int(np.count_nonzero(~disp))
    first_mult = int(comm.tompi4py().exscan(n_mult) or 0)
    total = int(comm.tompi4py().allreduce(n_mult))
    idx = first_mult + np.arange(n_mult)
    schur = coo_matrix(comm, idx, idx, -kappa[owned[~disp] - n] / gamma, (n_mult, total), (n_mult, total))
    split = {"transform": U, "schur": schur, "displacements": first + np.flatnonzero(disp),
             "multipliers": first + np.flatnonzero(~disp)}
    return LinearSolver("schur", near_null_space=modes, split=split)


def solve_distributed(scene, *, progress=False, comm=None, method="metis", parts=None, parallel_output=None,
                      samples_per_element=8):
    """Solve a scene with distributed assembly and solve (see the module docstring).

    Parameters
    ----------
    scene : Scene
    progress : bool
        True prints one line per load step on rank 0.
    comm : PETSc.Comm, optional
        Default ``PETSc.COMM_WORLD``.
    method : {"metis", "geometric"}
        The partition (:func:`~.partition.partition`).
    parts : callable, optional
        ``parts(solid_mesh, beam_meshes, n_ranks)`` returning ``(solid_part, beam_part)``: a given
        partition instead (e.g. one that leaves ranks empty).
    parallel_output : path, optional
        A directory (seen by every rank) where each rank writes its owned elements of every state as
        ``.vtu`` pieces and rank 0 the ``.pvtu`` files and ``result.pvd`` (:mod:`.output`).
    samples_per_element : int
        Samples of each beam element in ``parallel_output``.

    Returns
    -------
    Result on rank 0, None on the other ranks.
    """
    from ..model.build import build
    from ..model.model import Model
    from ..model.solve import _print_step
    from ..result import Result
    from ..solvers.newton import solve_linear_step, solve_load_steps
    from .system import DistributedSystem, OwnedPhysics
    PETSc = petsc()
    comm = PETSc.COMM_WORLD if comm is None else comm
    rank, size = comm.getRank(), comm.getSize()
    start = time.perf_counter()
    clock = _Clock(comm)
    model = Model(build(scene))
    reason = _unsupported(model)
    if reason:
        raise SceneError(reason)
    # dead loads on every rank (replicated input), body loads per owned element below
    model._body_loads = _BodyLoads()
    model.solid_physics = model._body_loads
    model._prepare_loads()
    clock("setup")
    beam_meshes = [g.mesh for g in model.groups]
    if parts is None:
        part = _agreed_partition(model.solid_mesh, beam_meshes, comm, method)
    else:
        solid_part, beam_part = parts(model.solid_mesh, beam_meshes, size)
        part = partition(model.solid_mesh, beam_meshes, size, solid_part=solid_part, beam_part=beam_part)
    numbering = Numbering.of(part, model.solid_mesh, beam_meshes, scene.coupling["lm"] if scene.coupled else "line2",
                             [g.type for g in model.groups])
    layout = SystemLayout.of(numbering, model.dofmap, [g.type.dofs_per_node for g in model.groups])
    clock("partition")
    ops, coupling, lagrange, kappa_rows, weighted, lm_rows = [], None, model.lagrange, None, None, None
    rotational, first_multiplier = [], []
    if scene.coupled:
        ops, kappa = _group_operators(model, part, numbering, comm)
        # the rotational coupling's parts; its multipliers follow the positional ones
        rotational, rotational_owners = rotational_parts(model, ops, part, numbering, comm)
        maps, owners = _multipliers(model, numbering, kappa) if lagrange else ([], np.zeros(0, np.int64))
        if len(owners) + len(rotational_owners):
            layout = layout.with_multipliers(np.concatenate([owners, rotational_owners]))
        first_multiplier = model.n_displacement_dofs + len(owners) + np.cumsum(
            [0] + [p.n_multipliers for p in rotational[:-1]], dtype=np.int64)
        if lagrange:
            coupling = _saddle_matrix(model, ops, numbering, layout, maps, comm)
            kappa_rows = np.concatenate([np.repeat(k[coupled_nodes(k)], 3) for k in kappa])
            # λ of the output: the multipliers of the state (−1: an LM row without one)
            n = model.n_displacement_dofs
            serial = [m[num.dofs(np.arange(3 * num.n), 3)] for m, num in zip(maps, numbering.lm)]
            lm_rows = [np.where(s >= 0, layout.of_serial[n + np.maximum(s, 0)], -1) for s in serial]
        else:
            coupling, weighted, lm_rows = _penalty_matrix(model, ops, numbering, layout, comm)
    clock("coupling")
    physics = OwnedPhysics(model, part, layout, rank)         # in the numbering of all unknowns
    physics.read_also(np.concatenate([np.zeros(0, np.int64)] + [p.reads(f) for p, f in zip(rotational,
                                                                                          first_multiplier)]))
    for p, f in zip(rotational, first_multiplier):
        p.bind(layout, physics, f)
    clock("stiffness")
    # the serial model on rank 0 from the gathered operators, before any solve: its preparation runs
    # the serial checks of the supports (rigid-body and zero-energy modes), which stop every rank
    served, dependent, dropped = _served_model(model, ops, numbering, comm), None, ()
    multipliers = lagrange or model.rotational_lagrange
    if multipliers:
        # the serial check of dependent multiplier rows, on rank 0 (same rows, same warning, same
        # SceneError); the other ranks learn which multipliers are left out
        found = None
        if rank == 0:
            try:
                dependent = _dependent_rows(served)
                found = dependent.rows
            except SceneError as exc:
                found = exc
        found = _raise_together(comm, found)
        if model.rotational_lagrange and len(found):
            # their least-norm λ is a projection along the state-dependent rotational rows: not the
            # fixed one that rank 0 applies to the gathered states
            raise SceneError("coupling.rotational: dependent multiplier rows (the warning above) are not "
                             "distributed yet with rotational multipliers; use backend = \"serial\"")
        dropped = found
    system = DistributedSystem(model, physics, layout, coupling, physics.body_forces(model._body_loads.values),
                               _linear_solver(model, layout, comm, coupling, kappa_rows), comm,
                               dropped=dropped, rotational=rotational)
    if system.solver.method == "aux":
        from .auxiliary import beam_solve_rows, follow_matrix
        system.solver.auxiliary["follow"] = follow_matrix(model, ops, kappa, numbering, layout, part, comm,
                                                          rotation=system.rotation)
        system.solver.auxiliary["solve_rows"] = beam_solve_rows(model, part, layout, rank)
    clock("loads_supports")
    callback = _print_step if (progress is True and rank == 0) else None
    z0 = np.zeros(system.sizes[0])                           # this rank's part of the iterate
    # a PETSc log stage of its own: with PETSc's logging on (-log_view), the messages and bytes the
    # load steps send are reported apart from the set-up (benchmarks/distributed_scaling.py reads them)
    stage = PETSc.Log.Stage("mortar1d3d solve")
    stage.push()
    try:
        if model.linear:
            z, record, linear_residual = solve_linear_step(system, z0, started=start)
            records, history = [record], [z.copy()]
            if callback:
                callback(record, 1, 1)
        else:
            a = scene.analysis
            z, records, history = solve_load_steps(system, z0, a["steps"], rtol=a["rtol"], increment_rtol=a["rtol"],
                                                   max_iterations=a["max_iterations"], max_cuts=a["max_cuts"],
                                                   progress=callback)
    finally:
        # the kept preconditioner (the sweep, its GAMG, its tangents) and E, also after a failed solve
        stage.pop()
        system.solver.close()
        for p in rotational:
            p.close()
        if system.solver.auxiliary:
            system.solver.auxiliary["follow"].destroy()
    clock("solve")
    # the solution, the history and the last residual (the reactions) in the serial numbering, on rank 0
    history_local = history
    z, history = system.gather(z), [system.gather(h) for h in history]
    last_residual = system.gather(linear_residual if model.linear else system.last_residual)
    relaxed = bool(lagrange and len(dropped))
    if relaxed:
        # λ of the left-out rows: the least-norm multipliers transferring the same forces, as the
        # serial saddle-point solver gives them (a linear projection: of the sum as of each increment)
        if rank == 0:
            n = model.n_displacement_dofs
            for v in [z] + history:
                v[n:] = dependent.least_norm(v[n:], kappa_rows)
    if parallel_output is not None:
        from .output import LineLoads, write_pieces
        if relaxed:
            # every rank's part of the states again, with the least-norm λ
            history_local = [system.scatter_from_root(h) for h in history]
        lines = LineLoads(model, physics, lm_rows, weighted, system.load) if scene.coupled else None
        # the pieces show physical components (clamped tangents back from their rotated frames) of
        # the unknowns each rank's elements read (one ghost update per state), and the line load
        states = [(0.0, np.zeros(len(physics.needed)), lines and lines.zero())]
        for rec, h in zip(records, history_local):
            x = system.physical(h)
            states.append((rec.load_factor, system.ghosted(x), lines and lines.at(x)))
            x.destroy()
        write_pieces(parallel_output, model, physics, states, comm, samples_per_element, lines=lines)
        clock("output")
    if weighted is not None:
        weighted.destroy()
    info_solve = system.last_linear_info or {}
    info = {"ranks": size, "unknowns": system.n_unknowns, "owned": np.diff(layout.ranges).tolist(),
            "iterations": info_solve.get("iterations"),
            "ksp": info_solve.get("ksp"), "pc": info_solve.get("pc"), "partition": part.stats,
            "linear_solves": {**system.linear_totals, "builds": system.solver.builds, "reuses": system.solver.reuses},
            "timings": clock.times, "cpu": comm.tompi4py().allgather(clock.cpu),
            "memory": comm.tompi4py().allgather(clock.memory),
            "traffic": {**_traffic(system.last_tangent, comm),
                        "ghost_entries": comm.tompi4py().allgather(system.ghost_entries),
                        "ghost_updates": system.ghost_updates}}
    if rank != 0:
        return None
    if model.linear:
        check_linear_displacements(served, z)      # warns as the serial solve does (on rank 0)
    # the reactions come from the last residual: of the linear step (r(z0) + K (z - z0), as the serial
    # path keeps it) or of the last Newton iterate
    served.last_residual = last_residual
    note = f"PETSc {info['ksp']} + {info['pc']} on {size} rank(s): {info['iterations']} iterations (last solve)"
    for rec in records:
        rec.notes.append(note)
    result = Result(served, z, records, history, wall_time=time.perf_counter() - start)
    result.distributed = info
    return result


def _served_model(model, ops, numbering, comm):
    """Collective: the serial model prepared with the gathered operators on rank 0 (no serial
    mortar assembly), which builds the Result; None on the other ranks.

    Preparing it runs the serial checks of the supports (:meth:`~mortar1d3d.model.model.Model.check_supports`);
    a SceneError they raise on rank 0 is raised on every rank (none waits for rank 0 in a later
    collective call)."""
    from ..model.model import Model
    # every rank sends its part of the operators and points, rank 0 keeps them
    outputs = [(d.gathered(), _gathered_points(comm, d.local)) for d in ops]
    served = None
    if comm.getRank() == 0:
        try:
            gathered = [_serial_operators(model, g, out, numbering, k)
                        for k, (g, out) in enumerate(zip(model.groups, outputs))]
            served = Model(model_built(model)).prepare(operators=gathered or None)
        except SceneError as exc:
            served = exc
    _raise_together(comm, served if isinstance(served, SceneError) else None)
    return served


def _agreed_partition(solid, beam_meshes, comm, method):
    """The partition, computed by METIS on rank 0 only and sent to every rank.

    Every rank must hold the same owners: ranks that disagree would number the unknowns
    differently and add entries to rows nobody owns, or wait for each other forever. The
    geometric partition is plain array arithmetic on the same input, but METIS is another
    library whose result may differ between builds or machines of one cluster; so rank 0 cuts
    the graph and broadcasts the owner arrays (one integer per element). An error on rank 0
    (pymetis missing there) is raised on every rank.
    """
    size = comm.getSize()
    if size == 1 or method != "metis":
        return partition(solid, beam_meshes, size, method)
    part, owners = None, None
    if comm.getRank() == 0:
        try:
            part = partition(solid, beam_meshes, size, method)
            owners = (part.solid_part, part.beam_part)
        except Exception as exc:      # sent to every rank and raised there
            owners = exc
    owners = comm.tompi4py().bcast(owners, root=0)
    if isinstance(owners, Exception):
        raise owners
    if part is not None:
        return part
    part = partition(solid, beam_meshes, size, solid_part=owners[0], beam_part=owners[1])
    part.method = method
    return part


def _raise_together(comm, found):
    """Collective: rank 0's ``found`` on every rank, raised there as a SceneError if it is one."""
    found = comm.tompi4py().bcast(found, root=0)
    if isinstance(found, SceneError):
        raise SceneError(str(found))
    return found


def _dependent_rows(served):
    """The dependent multiplier rows of the prepared serial model ``served`` as its Lagrange solve
    finds them (:meth:`~mortar1d3d.model.model.Model._dependent_multipliers`: the constraint rows on
    the free displacement unknowns, in the unknowns' basis; it warns, or raises SceneError)."""
    n = served.n_displacement_dofs
    # the rotational multipliers' rows at the reference state (the serial model checks them in its
    # first linear solve, at the first iterate)
    B = sp.vstack(([served.constraint_matrix] if served.lagrange else [])
                  + [g.rotational.reference_rows()[g.rotational.coupled_rows] for g in served.groups
                     if g.rotational is not None and g.rotational.enforcement == "lagrange"], format="csr")
    if served.basis:
        B = B @ served.basis.matrix_T(n)
    free = served.free[served.free < n]
    return served._dependent_multipliers(B.tocsr()[:, free], np.flatnonzero(free >= 3 * served.n_solid_nodes))


def model_built(model):
    """The built scene of ``model`` again (its meshes and sets, without a second build)."""
    from ..model.build import BuiltScene
    from ..model.dofmap import DofMap
    dofmap = DofMap(model.dofmap.blocks)
    return BuiltScene(scene=model.scene, solid_mesh=model.solid_mesh, groups=model.groups,
                      entry_group=model.entry_group, sets=model.sets, dofmap=dofmap)


def _gathered_points(comm, local):
    """Every rank's integration points and segments with serial ids, concatenated on rank 0 in the
    serial order (by beam element; within one, the rank's own order): (point_fields, segments)."""
    parts = comm.tompi4py().gather(local.serial_points(), root=0)
    if comm.getRank() != 0:
        return None
    parts = [p for p in parts if p[0] is not None]
    from ..mortar.assemble import POINT_DTYPE, SEGMENT_DTYPE
    if not parts:
        return ({name: np.zeros((0,) + POINT_DTYPE[name].shape, POINT_DTYPE[name].base) for name in POINT_DTYPE.names},
                np.zeros(0, SEGMENT_DTYPE))
    fields = {name: np.concatenate([p[0][name] for p in parts]) for name in parts[0][0]}
    order = np.argsort(fields["beam_element"], kind="stable")
    fields = {name: values[order] for name, values in fields.items()}
    segments = np.concatenate([p[1] for p in parts])
    return fields, segments[np.argsort(segments["beam_element"], kind="stable")]


def _serial_operators(model, g, output, numbering, k):
    """MortarOperators in the serial numbering from the gathered distributed D, M, κ (rank 0's output)."""
    from ..mortar.assemble import MortarOperators
    from .assemble import renumbered
    (D, M, kappa), (fields, segments) = output
    per_node = g.type.dofs_per_node
    lm = numbering.lm[k]
    old_rows = np.empty(D.shape[0], dtype=np.int64)
    old_rows[lm.dofs(np.arange(D.shape[0]), 3)] = np.arange(D.shape[0])
    old_beam = np.empty(D.shape[1], dtype=np.int64)
    old_beam[numbering.beams[k].dofs(np.arange(D.shape[1]), per_node)] = np.arange(D.shape[1])
    old_solid = np.empty(M.shape[1], dtype=np.int64)
    old_solid[numbering.solid.dofs(np.arange(M.shape[1]), 3)] = np.arange(M.shape[1])
    kappa_serial = kappa[lm.new_of_old]
    c = model.scene.coupling
    return MortarOperators(D=renumbered(D, old_rows, old_beam, D.shape), M=renumbered(M, old_rows, old_solid, M.shape),
                           kappa=kappa_serial, segments=segments, point_fields=fields, n_lm=len(kappa),
                           integration=c["integration"], n_gauss=c["n_gauss"], lm=c["lm"],
                           embedded_length=float(kappa.sum()), beam_length=g.mesh.length,
                           constraint_residual=float("nan"))
