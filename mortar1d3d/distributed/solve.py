"""The linear penalty model on PETSc: distributed stiffness, CG + GAMG, the result gathered on rank 0.

``solve(scene)`` with ``analysis.backend = "petsc"`` comes here (under ``mpiexec -n N``; one rank
works too). Every rank reads the scene and builds the serial meshes, sets, supports and loads (the
input is replicated in this first slice); the work that grows with the model is distributed:

* :func:`~.partition.partition` gives each rank its solid and beam elements;
* each rank assembles the linear stiffness of its owned solid elements and owned beam elements
  with the serial physics (the same Numba kernels, on meshes of its elements) and its part of D,
  M and κ (:mod:`.assemble`), all added into one PETSc ``MPIAIJ`` matrix in the system numbering
  (:class:`SystemLayout`: per rank its solid nodes, then its nodes of each beam group);
* the penalty stiffness ε Bᵀ diag(κ)⁻¹ B (B = [−M, D], docs/conventions.md §1) is formed by PETSc
  from the distributed B and κ;
* supports by ``MatZeroRowsColumns`` (symmetric, the prescribed values moved to the right side);
* CG with PETSc's algebraic multigrid GAMG, given the model's rigid-body modes as near-null space
  (``analysis.solver`` = ``"auto"`` or ``"amg"``), or a parallel LU (MUMPS) for ``"direct"``.

The solution is gathered on rank 0, which builds the :class:`~mortar1d3d.result.Result` from the
gathered operators (no serial mortar assembly); the other ranks return None.
"""
import time
from dataclasses import dataclass

import numpy as np

from ..scene import SceneError
from .assemble import assemble_distributed, beam_submesh, solid_submesh
from .numbering import Numbering
from .partition import partition
from .petsc import coo_matrix, gather_vector, petsc, summed_vector


@dataclass(frozen=True)
class SystemLayout:
    """The system's rank-major numbering: rank r owns ``[its solid node DOFs | its group-0 beam node
    DOFs | group 1 | ...]``, one contiguous range ``ranges[r]:ranges[r + 1]``.

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
    if not model.linear:
        return "analysis.kinematics: the PETSc backend solves linear analyses so far; use \"linear\" or backend = \"serial\""
    if sc.coupled and (sc.coupling["enforcement"] != "penalty" or sc.coupling["constraint"] != "mortar"):
        return ("coupling.enforcement: the PETSc backend couples with mortar penalty so far (Lagrange multipliers "
                "and the Gauss-point constraint run with backend = \"serial\")")
    if sc.coupled and sc.coupling.get("rotational") is not None:
        return "coupling.rotational: not distributed yet; use backend = \"serial\""
    if any(g.rotations.size for g in model.groups):
        return "beams[..].model: beams with rotations (simo_reissner) are not distributed yet; use backend = \"serial\""
    if any(d["clamp"] for d in sc.dirichlet):
        return "dirichlet[..].clamp: clamps (rotated tangent frames) are not distributed yet; use backend = \"serial\""
    if sc.solid is not None and sc.solid["material"].get("fibres"):
        return "solid.material.fibres: fibre-reinforced materials are not distributed yet; use backend = \"serial\""
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


def _entry_of_elements(g):
    entry = np.empty(g.mesh.n_elements, dtype=np.int64)
    for k, (a, b) in enumerate(g.entry_elements):
        entry[a:b] = g.entries[k]
    return entry


def _stiffness_triplets(model, part, layout, rank):
    """This rank's solid and beam stiffness entries and body forces, in system numbering."""
    from ..physics.materials import material
    from ..physics.solid import SolidModel
    rows, cols, vals, f_idx, f_val = [], [], [], [], []
    mat = model.scene.solid["material"]
    sub, nodes = solid_submesh(model.solid_mesh, part.owned_solid(rank))
    if sub is not None:
        physics = SolidModel(sub, material(mat["model"], mat["E"], mat["nu"]), kinematics="linear")
        _, K = physics.evaluate(np.zeros(physics.n_dofs))
        K = K.tocoo()
        serial = 3 * nodes[:, None] + np.arange(3)[None, :]
        to_system = layout.of_serial[serial.ravel()]
        rows.append(to_system[K.row]), cols.append(to_system[K.col]), vals.append(K.data)
        for b in model._body_loads.values:
            f_idx.append(to_system), f_val.append(physics.body_force(b))
    for k, g in enumerate(model.groups):
        owned = part.owned_beams(rank, k)
        mesh, nodes = beam_submesh(g.mesh, owned)
        if mesh is None:
            continue
        entries = _entry_of_elements(g)[owned]
        physics = g.type.make_physics(mesh, [(1, model.scene.beams[e]["section"]) for e in entries])
        per_node = g.type.dofs_per_node
        _, K = physics.evaluate(np.zeros(mesh.n_centreline_dofs))
        K = K.tocoo()
        serial = g.dofs.start + per_node * nodes[:, None] + np.arange(per_node)[None, :]
        to_system = layout.of_serial[serial.ravel()]
        rows.append(to_system[K.row]), cols.append(to_system[K.col]), vals.append(K.data)
    cat = (lambda parts, dt: np.concatenate(parts).astype(dt) if parts else np.zeros(0, dt))
    return (cat(rows, np.int64), cat(cols, np.int64), cat(vals, float)), (cat(f_idx, np.int64), cat(f_val, float))


def _coupling_matrix(model, part, numbering, layout, comm):
    """B = [−M, D] of every group in system columns (rows: the groups' LM rows, rank-major per rank),
    the summed κ per row, and each group's distributed operators."""
    rank, n_parts = comm.getRank(), comm.getSize()
    c = model.scene.coupling
    options = {k: c[k] for k in ("integration", "n_gauss", "lm", "search_points")}
    # rows: per rank, its LM rows of group 0, then of group 1, ...
    counts = np.array([[3 * num.count(r) for num in numbering.lm] for r in range(n_parts)], dtype=np.int64)
    row_ranges = np.concatenate([[0], np.cumsum(counts.sum(axis=1))])
    rows, cols, vals, k_idx, k_val, ops = [], [], [], [], [], []
    for k, g in enumerate(model.groups):
        dist = assemble_distributed(model.solid_mesh, g.mesh, part, numbering, group=k, comm=comm, **options)
        ops.append(dist)
        num = numbering.lm[k]
        per_node = g.type.dofs_per_node

        def row_of(new_rows, num=num, k=k):
            # the rank that owns a rank-major LM node: the range it falls in
            lm_rank = np.searchsorted(num.ranges, new_rows // 3, side="right") - 1
            return row_ranges[lm_rank] + counts[lm_rank, :k].sum(axis=1) + new_rows - 3 * num.ranges[lm_rank]

        # operator columns (rank-major per kind) back to serial, then to the system
        beam_serial = np.empty(g.dofs.size, dtype=np.int64)
        beam_serial[numbering.beams[k].dofs(np.arange(g.dofs.size), per_node)] = np.arange(g.dofs.size) + g.dofs.start
        solid_serial = np.empty(3 * model.n_solid_nodes, dtype=np.int64)
        solid_serial[numbering.solid.dofs(np.arange(3 * model.n_solid_nodes), 3)] = np.arange(3 * model.n_solid_nodes)
        r, cc, v = dist.local.D
        rows.append(row_of(r)), cols.append(layout.of_serial[beam_serial[cc]]), vals.append(v)
        r, cc, v = dist.local.M
        rows.append(row_of(r)), cols.append(layout.of_serial[solid_serial[cc]]), vals.append(-v)
        lm_new, kappa = dist.local.kappa
        three = (3 * lm_new[:, None] + np.arange(3)[None, :]).ravel()
        k_idx.append(row_of(three)), k_val.append(np.repeat(kappa, 3))
    n_rows = int(row_ranges[-1])
    local_rows = int(row_ranges[rank + 1] - row_ranges[rank])
    n_sys = int(layout.ranges[-1])
    local_sys = int(layout.ranges[rank + 1] - layout.ranges[rank])
    B = coo_matrix(comm, np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), (local_rows, n_rows),
                   (local_sys, n_sys))
    kappa = summed_vector(comm, np.concatenate(k_idx), np.concatenate(k_val), (local_rows, n_rows))
    return B, kappa, ops


class _Clock:
    """Per stage: the wall time of the slowest rank (a barrier before each reading), and this rank's
    CPU time up to the barrier (its own work; on a loaded machine the fairer measure of balance)."""

    def __init__(self, comm):
        self.comm, self.times, self.cpu = comm, {}, {}
        self.last, self.last_cpu = time.perf_counter(), time.process_time()

    def __call__(self, stage):
        now_cpu = time.process_time()
        self.cpu[stage] = now_cpu - self.last_cpu
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


def _near_null_space(model, layout, rank, A):
    """The model's rigid-body modes (translations, rotations; tangent DOFs rotate) as a PETSc null space."""
    PETSc = petsc()
    R = model.rigid_body_modes()                              # serial numbering, (n, 6)
    owned_serial = layout.owned_serial(rank)
    vecs = []
    for j in range(R.shape[1]):
        v = A.createVecRight()
        v.setArray(np.ascontiguousarray(R[owned_serial, j]))
        vecs.append(v)
    # PETSc wants an orthonormal basis
    for j, v in enumerate(vecs):
        for u in vecs[:j]:
            v.axpy(-v.dot(u), u)
        v.normalize()
    return PETSc.NullSpace().create(vectors=vecs, comm=A.getComm())


def solve_distributed(scene, *, progress=False, comm=None, method="metis", parts=None):
    """Solve a linear penalty scene with distributed assembly and solve (see the module docstring).

    Parameters
    ----------
    scene : Scene
    progress : bool
        True prints the solve's line on rank 0.
    comm : PETSc.Comm, optional
        Default ``PETSc.COMM_WORLD``.
    method : {"metis", "geometric"}
        The partition (:func:`~.partition.partition`).
    parts : callable, optional
        ``parts(solid_mesh, beam_meshes, n_ranks)`` returning ``(solid_part, beam_part)``: a given
        partition instead (e.g. one that leaves ranks empty).

    Returns
    -------
    Result on rank 0, None on the other ranks.
    """
    from ..model.build import build
    from ..model.model import Model
    from ..result import Result
    from ..solvers.newton import StepRecord
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
        part = partition(model.solid_mesh, beam_meshes, size, method)
    else:
        solid_part, beam_part = parts(model.solid_mesh, beam_meshes, size)
        part = partition(model.solid_mesh, beam_meshes, size, solid_part=solid_part, beam_part=beam_part)
    numbering = Numbering.of(part, model.solid_mesh, beam_meshes, scene.coupling["lm"] if scene.coupled else "line2")
    layout = SystemLayout.of(numbering, model.dofmap, [g.type.dofs_per_node for g in model.groups])
    n_sys = int(layout.ranges[-1])
    local = int(layout.ranges[rank + 1] - layout.ranges[rank])
    clock("partition")
    (r, c, v), (f_idx, f_val) = _stiffness_triplets(model, part, layout, rank)
    A = coo_matrix(comm, r, c, v, (local, n_sys), (local, n_sys), block_size=3)
    clock("stiffness")
    ops = []
    if scene.coupled:
        B, kappa, ops = _coupling_matrix(model, part, numbering, layout, comm)
        w = kappa.copy()
        arr = w.getArray()
        arr[arr > 0] = model.penalty / arr[arr > 0]
        w.setArray(arr)
        WB = B.copy()
        WB.diagonalScale(L=w)
        Kc = B.transposeMatMult(WB)
        A.axpy(1.0, Kc, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    clock("coupling")
    # loads: the replicated dead loads on their owners, the body forces added by PETSc
    b = A.createVecLeft()
    owned_serial = layout.owned_serial(rank)
    b.setArray(model.dead_load[owned_serial])
    if len(f_idx):
        b.setValues(f_idx.astype(PETSc.IntType), f_val, addv=PETSc.InsertMode.ADD_VALUES)
    b.assemblyBegin()
    b.assemblyEnd()
    # supports: symmetric elimination, prescribed values to the right-hand side
    x = A.createVecRight()
    x.set(0.0)
    fixed_sys = layout.of_serial[model.fixed_dofs]
    first = int(layout.ranges[rank])
    keep = (fixed_sys >= first) & (fixed_sys < first + local)
    rows = fixed_sys[keep].astype(PETSc.IntType)
    x.setValues(rows, model.prescribed(1.0)[keep])
    x.assemblyBegin()
    x.assemblyEnd()
    A.zeroRowsColumns(rows, diag=1.0, x=x, b=b)
    A.setNearNullSpace(_near_null_space(model, layout, rank, A))
    ksp = PETSc.KSP().create(comm=comm)
    ksp.setOperators(A)
    solver = scene.analysis["solver"]
    if solver == "direct":
        ksp.setType(PETSc.KSP.Type.PREONLY)
        ksp.getPC().setType(PETSc.PC.Type.LU)
        ksp.getPC().setFactorSolverType("mumps")
    else:
        ksp.setType(PETSc.KSP.Type.CG)
        # the true residual, as analysis.rtol means for the serial solvers (not the preconditioned one)
        ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        ksp.getPC().setType(PETSc.PC.Type.GAMG)
        ksp.setTolerances(rtol=scene.analysis["rtol"], atol=0.0, max_it=10000)
    ksp.setFromOptions()
    clock("loads_supports")
    ksp.solve(b, x)
    clock("solve")
    reason = ksp.getConvergedReason()
    if reason < 0:
        from ..solvers.newton import ConvergenceError
        raise ConvergenceError(f"PETSc KSP {ksp.getType()} with {ksp.getPC().getType()} did not converge "
                               f"(reason {reason}) after {ksp.getIterationNumber()} iterations")
    iterations = ksp.getIterationNumber()
    x_all = gather_vector(x)
    # collective: every rank sends its part of the operators and points, rank 0 keeps them
    outputs = [(d.gathered(), _gathered_points(comm, d.local)) for d in ops]
    info = {"ranks": size, "unknowns": n_sys, "iterations": iterations, "ksp": ksp.getType(),
            "pc": ksp.getPC().getType(), "partition": part.stats, "timings": clock.times,
            "cpu": comm.tompi4py().allgather(clock.cpu),
            "traffic": _traffic(A, comm)}
    if rank != 0:
        return None
    z = np.zeros(model.n_displacement_dofs)
    z[:] = x_all[layout.of_serial]
    gathered = [_serial_operators(model, g, out, numbering, k) for k, (g, out) in enumerate(zip(model.groups, outputs))]
    served = Model(model_built(model))
    served.prepare(operators=gathered or None)
    record = StepRecord(load_factor=1.0, iterations=1, residuals=[], increments=[float(np.linalg.norm(z))],
                        time=time.perf_counter() - start,
                        notes=[f"PETSc {info['ksp']} + {info['pc']} on {size} rank(s): {iterations} iterations"])
    if progress is True:
        print(f"  step    1  load factor   1.0000  {record.notes[0]}  {record.time:6.2f} s", flush=True)
    result = Result(served, z, [record], [z.copy()], wall_time=time.perf_counter() - start)
    result.distributed = info
    return result


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
