"""The model's nonlinear system on PETSc: what :mod:`mortar1d3d.solvers.newton` iterates on.

:class:`DistributedSystem` follows the protocol of :mod:`mortar1d3d.solvers.newton` (``fixed``,
``free``, ``prescribed``, ``residual``, ``solve_linear``, plus ``free_block`` and ``product``),
so the library's own load steps, Newton iterations and convergence tests run unchanged on every
rank. What grows with the model is distributed:

* each rank evaluates the internal forces and tangents of its owned solid elements and owned beam
  elements with the serial physics (the unchanged Numba kernels, on meshes of its elements,
  :class:`OwnedPhysics`) and adds them into a PETSc vector and ``MPIAIJ`` matrix in the system
  numbering (:class:`~.solve.SystemLayout`); entries of rows another rank owns go through PETSc's
  assembly;
* the coupling is one constant distributed matrix ``C`` (formed once by PETSc from the distributed
  D, M, κ): the penalty stiffness ε Bᵀ diag(κ)⁻¹ B, or, with Lagrange multipliers, the saddle
  block ``[[0, Bᵀ], [B, 0]]`` (B = [−M, D] on the coupled LM rows); the residual adds ``C z``, the
  tangent ``C``;
* the Newton increment is solved by PETSc KSP (:mod:`.linear`).

The iterate ``z``, the residual handed to the Newton loop and the increment are distributed: each
rank holds the entries it owns, in the order of its range of the system numbering (the local part
of a PETSc vector, copied into one of the system's layout when PETSc computes with it, without
communication). The loop's
elementwise steps run on these parts unchanged, and its norms are global (:meth:`norm`, the same
number on every rank, so that every rank takes the same decisions). Before each evaluation of the
physics one ``VecScatter`` brings each rank the unknowns of its owned elements' nodes that other
ranks own (the ghosts: the nodes its elements share with the neighbours' elements); nothing is
gathered while the loop runs. The solution is gathered on rank 0 at the end, for the Result.
"""
import math

import copy

import numpy as np
import scipy.sparse as sp

from .assemble import beam_submesh, solid_submesh
from .petsc import Entries, coo_matrix, petsc, summed_vector


def _entry_of_elements(g):
    """Scene beam entry of every element of group ``g``."""
    entry = np.empty(g.mesh.n_elements, dtype=np.int64)
    for k, (a, b) in enumerate(g.entry_elements):
        entry[a:b] = g.entries[k]
    return entry


def owned_beam_physics(model, k, owned):
    """The physics of the beam elements ``owned`` (ascending) of group ``k`` on a mesh of their
    own: ``(mesh, its nodes' serial ids, physics, serial rotation nodes)``. A group with rotations
    gets the serial reference triads and rules of its rotation nodes (the sub-mesh's nodes, then its
    elements' middle nodes: the sub-mesh's rotation nodes in their order); otherwise the last is
    None, and everything is None without elements."""
    g = model.groups[k]
    mesh, nodes = beam_submesh(g.mesh, owned)
    if mesh is None:
        return None, nodes, None, None
    # one (count, section) per run of consecutive owned elements of one scene entry, as the serial
    # model passes one per entry (not one per element: a Python list per element at set-up)
    entry = _entry_of_elements(g)[owned]
    starts = np.flatnonzero(np.r_[True, entry[1:] != entry[:-1]])
    counts = np.diff(np.r_[starts, len(entry)])
    specs = [model.scene.beams[e] for e in entry[starts]]
    sections = [(int(n), spec["section"]) for n, spec in zip(counts, specs)]
    if not g.rotations.size:
        return mesh, nodes, g.type.make_physics(mesh, sections), None
    rotation_nodes = np.concatenate([nodes, g.mesh.n_nodes + owned])
    return mesh, nodes, g.type.make_physics(mesh, sections, g.triads[rotation_nodes],
                                            [spec.get("force_rule") for spec in specs],
                                            [spec.get("virtual_spins") for spec in specs]), rotation_nodes


class OwnedPhysics:
    """The solid and beam physics of one rank's owned elements, with their unknowns in the system numbering.

    Parameters
    ----------
    model : Model
        Built (not prepared) on every rank.
    part : Partition
    layout : SystemLayout
    rank : int
    """

    def __init__(self, model, part, layout, rank):
        from ..physics.materials import material
        from ..physics.solid import SolidModel
        from ..physics.surface import Pressure
        self.parts = []          # (physics, serial unknowns of its DOFs, system indices, their place in `needed`)
        kinematics = "linear" if model.linear else "nonlinear"
        mat = model.scene.solid["material"]
        self.solid_elements = part.owned_solid(rank)
        sub, self.solid_nodes = solid_submesh(model.solid_mesh, self.solid_elements)
        self.solid, self.pressures, self.moments = None, [], []
        if sub is not None:
            # the fibre families of the owned elements: the serial field's sets, each element's own
            fibres = copy.copy(model._fibre_field(mat.get("fibres", ())))
            fibres.element_set = np.ascontiguousarray(fibres.element_set[self.solid_elements])
            self.solid = SolidModel(sub, material(mat["model"], mat["E"], mat["nu"]), kinematics=kinematics,
                                    fibres=fibres)
            serial = (3 * self.solid_nodes[:, None] + np.arange(3)[None, :]).ravel()
            self.parts.append((self.solid, serial, layout.of_serial[serial]))
            # follower pressures of a nonlinear analysis on the faces of the owned elements (the
            # sub-mesh keeps the serial order of its elements)
            for pressure in model.pressures:
                faces = pressure.faces[np.isin(pressure.faces["element"], self.solid_elements)].copy()
                faces["element"] = np.searchsorted(self.solid_elements, faces["element"])
                if len(faces):
                    self.pressures.append(Pressure(sub, faces, pressure.p))
        if rank == 0:
            # end moments of a nonlinear analysis (a few nodes): rank 0 adds them, PETSc sends them on
            self.moments = [(dofs, moment, layout.of_serial[dofs]) for dofs, moment in model.moments]
        reference = model.reference()
        self.beams = []          # per group with owned elements: (group, owned elements, their entries, mesh, its entry of `parts`)
        #: per group with rotations and owned elements: its physics (:class:`_Framed`)
        self.framed = {}
        for k, g in enumerate(model.groups):
            owned = part.owned_beams(rank, k)
            mesh, nodes, physics, rotation_nodes = owned_beam_physics(model, k, owned)
            if mesh is None:
                continue
            entries = _entry_of_elements(g)[owned]
            per_node = g.type.dofs_per_node
            serial = (g.dofs.start + per_node * nodes[:, None] + np.arange(per_node)[None, :]).ravel()
            if rotation_nodes is not None:
                physics = _Framed(physics)
                serial = np.concatenate([serial, g.rotations.dofs(rotation_nodes, [0, 1, 2])])
                self.framed[k] = physics
            self.parts.append((physics, serial, layout.of_serial[serial]))
            self.beams.append((k, owned, entries, mesh, len(self.parts) - 1))
        self._unindexed = (self.parts, [(reference[dofs], moment, system, dofs) for dofs, moment, system in self.moments],
                           self.beams, [])
        self.read_also(np.zeros(0, np.int64))

    def read_also(self, serial):
        """Adds the serial unknowns ``serial`` to those each evaluation reads (:attr:`needed`), for
        a term evaluated beside this physics (the rotational coupling: the solid nodes of the
        elements its beams reach, its multipliers); before the system's ghost update is made."""
        parts, moments, beams, extra = self._unindexed
        extra.append(np.asarray(serial, dtype=np.int64))
        #: the serial unknowns this rank's evaluation reads (sorted): the displacements of its owned
        #: elements' nodes and of the end-moment nodes (and what `read_also` added); `evaluate`
        #: takes them in this order
        self.needed = np.unique(np.concatenate([serial for _, serial, _ in parts] + [dofs for *_, dofs in moments]
                                               + extra))
        self.parts = [(physics, serial, system, self.place(serial)) for physics, serial, system in parts]
        self.moments = [(reference, moment, system, self.place(dofs)) for reference, moment, system, dofs in moments]
        self.beams = [(k, owned, entries, mesh, self.parts[i]) for k, owned, entries, mesh, i in beams]

    def place(self, serial):
        """The places of the serial unknowns ``serial`` in :attr:`needed` (they must be there)."""
        return np.searchsorted(self.needed, serial)

    def solid_displacement(self, d):
        """(n_owned_solid_nodes, 3) displacements of the owned solid elements' nodes, from ``d`` (:attr:`needed` order)."""
        return d[self.parts[0][3]].reshape(-1, 3)

    def evaluate(self, d, tangent=True, t=1.0):
        """Internal forces minus the follower loads at load factor ``t``, and their tangent
        entries, at the (physical) displacements ``d`` of the unknowns :attr:`needed` (in that
        order), in system numbering.

        Returns
        -------
        forces : (index, values)
        tangent : (rows, cols, values) or None
        """
        idx, f_val, rows, cols, vals = [], [], [], [], []

        def add(system, f, K):
            idx.append(system), f_val.append(f)
            if tangent:
                K = sp.coo_matrix(K)
                rows.append(system[K.row]), cols.append(system[K.col]), vals.append(K.data)

        for physics, _, system, local in self.parts:
            add(system, *physics.evaluate(np.ascontiguousarray(d[local]), tangent=tangent))
        if self.pressures:
            # as Model.residual: the pressure is an external force, −t f in the residual, −t ∂f/∂u in K
            local = self.parts[0][3]
            for pressure in self.pressures:
                f, Kp = pressure.evaluate(d[local], tangent=tangent)
                add(self.parts[0][2], -t * f, -t * Kp if tangent else None)
        if self.moments:
            from ..physics.beam import end_moment
            for reference, moment, system, local in self.moments:
                f, Km = end_moment(reference + d[local], t * moment)
                add(system, -f, -Km if tangent else None)
        forces = (_cat(idx, np.int64), _cat(f_val, float))
        return forces, ((_cat(rows, np.int64), _cat(cols, np.int64), _cat(vals, float)) if tangent else None)

    def body_forces(self, values):
        """Consistent nodal forces of the body loads ``values`` (each (3,)) over the owned solid elements."""
        if self.solid is None or not values:
            return np.zeros(0, np.int64), np.zeros(0)
        system = self.parts[0][2]
        return np.tile(system, len(values)), np.concatenate([self.solid.body_force(b) for b in values])


class _Framed:
    """The physics of beams with rotations (``evaluate(d, psi)``, ``sample(d, psi, eta)``) on one
    vector of unknowns ``[centreline DOFs | ψ of the rotation nodes]``, as the other beam types'."""

    def __init__(self, physics):
        self.physics, self.n = physics, physics.n_centreline_dofs

    def _split(self, x):
        return x[:self.n], x[self.n:].reshape(-1, 3)

    def evaluate(self, x, tangent=True):
        return self.physics.evaluate(*self._split(x), tangent=tangent)

    def sample(self, x, eta):
        return self.physics.sample(*self._split(x), eta)

    def update(self, psi, spin):
        return self.physics.update(psi, spin)


def _cat(parts, dtype):
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype)


class DistributedSystem:
    """The Newton protocol of :mod:`mortar1d3d.solvers.newton` on PETSc (see the module docstring).

    Parameters
    ----------
    model : Model
        With its dead loads prepared (the replicated part of the loads).
    physics : OwnedPhysics
    layout : SystemLayout
        Over all unknowns (displacements, then multipliers, rank by rank).
    coupling : PETSc.Mat or None
        The constant coupling matrix ``C`` in the system numbering.
    body : (index, values)
        This rank's body forces (system numbering), added to the replicated dead load.
    solver : LinearSolver
        Solves the reduced tangent system (:mod:`.linear`).
    comm : PETSc.Comm
    dropped : (k,) int array, optional
        Multipliers (serial index among the multipliers) whose constraint rows depend on the
        others: held at zero like prescribed unknowns (the solve leaves their rows out, as the
        serial saddle-point solver does; the least-norm λ is formed from the result afterwards).

    With clamps (``model.basis``, :mod:`mortar1d3d.supports`) the iterate is in the basis of the
    unknowns, as in the serial model: the physics and the coupling are evaluated on physical
    components, and the residual and tangent are taken back to the unknowns' basis by PETSc
    (``Tᵀ r``, ``Tᵀ K T``) with ``T`` a distributed matrix of the rotated triplets.
    """

    def __init__(self, model, physics, layout, coupling, body, solver, comm, dropped=(), rotational=()):
        PETSc = petsc()
        self.model, self.physics, self.layout, self.coupling = model, physics, layout, coupling
        #: the rotational coupling's parts (:class:`~.rotational.RotationalPart`), bound to this layout
        self.rotational = list(rotational)
        self.solver, self.comm = solver, comm
        self.rank = comm.getRank()
        self.n = model.n_displacement_dofs
        self.n_unknowns = len(layout.of_serial)
        self.dropped = self.n + np.asarray(dropped, dtype=np.int64)
        # serial: the model's supports, then the left-out multipliers (after the displacements)
        fixed_serial = np.concatenate([model.fixed_dofs, self.dropped])
        self.owned_serial = layout.owned_serial(self.rank)
        first = int(layout.ranges[self.rank])
        self.sizes = (int(layout.ranges[self.rank + 1]) - first, self.n_unknowns)
        fixed_system = layout.of_serial[fixed_serial]
        self._fixed_mine = (fixed_system >= first) & (fixed_system < first + self.sizes[0])
        # the Newton loop's `fixed` and `free`: places in this rank's part of the vectors
        self.fixed = fixed_system[self._fixed_mine] - first
        self.free = np.setdiff1d(np.arange(self.sizes[0]), self.fixed)
        self.fixed_rows = fixed_system[self._fixed_mine]
        self.dropped_rows = self.fixed_rows[fixed_serial[self._fixed_mine] >= self.n]
        self.basis = model.basis
        self.rotation = None
        if self.basis:
            T = self.basis.matrix_T(self.n_unknowns).tocoo()
            rows = layout.of_serial[T.row]
            mine = (rows >= first) & (rows < first + self.sizes[0])
            self.rotation = coo_matrix(comm, rows[mine], layout.of_serial[T.col[mine]], T.data[mine], self.sizes,
                                       self.sizes)
        dead = np.zeros(self.n_unknowns)
        dead[:self.n] = model.dead_load
        self.load = summed_vector(comm, *body, self.sizes)
        self.load.setArray(self.load.getArray() + dead[self.owned_serial])
        # the ghost update: the unknowns the owned elements read (physics.needed), from their owners
        needed = layout.of_serial[physics.needed]
        self._ghosts = Entries(self.load, needed)
        #: entries this rank receives from other ranks in each ghost update
        self.ghost_entries = int(np.count_nonzero((needed < first) | (needed >= first + self.sizes[0])))
        self.ghost_updates = 0
        reference = model.reference()
        self._reference = np.zeros(self.sizes[0])
        leading = self.owned_serial < len(reference)
        self._reference[leading] = reference[self.owned_serial[leading]]
        # the rotation nodes this rank owns, per group: the places of their three unknowns in its part
        # twist supports (Model._twist_jacobian): the first places of the held rotation triplets this
        # rank owns; their unknowns are total rotation vectors in their frames, updated additively
        self._twist_any = bool(model.twist_starts.size)
        twist = layout.of_serial[model.twist_starts]
        self._twist = twist[(twist >= first) & (twist < first + self.sizes[0])] - first
        self._spins = []
        for k, b in enumerate(model.dofmap.rotations):
            mine = np.flatnonzero((self.owned_serial >= b.start) & (self.owned_serial < b.stop)).reshape(-1, 3)
            mine = mine[~np.isin(mine[:, 0], self._twist)]
            if len(mine):
                self._spins.append((physics.framed[k], mine))
        self.last_linear_info = None
        #: over all linear solves so far: their count, KSP iterations, preconditioner set-up and
        #: solve wall seconds (this rank's clock; the set-up is collective)
        self.linear_totals = {"solves": 0, "iterations": 0, "setup_seconds": 0.0, "solve_seconds": 0.0}
        self.last_residual = self.last_tangent = None

    def prescribed(self, t):
        """Values of this rank's fixed unknowns (``fixed``) at load factor ``t``."""
        return np.concatenate([self.model.prescribed(t), np.zeros(len(self.dropped))])[self._fixed_mine]

    def reference(self):
        """The base configuration of this rank's unknowns (zero for the multipliers)."""
        return self._reference

    def update(self, z, free, dz):
        """Apply the Newton increment ``dz`` (on this rank's ``free`` unknowns) to its part ``z``, as
        :meth:`~mortar1d3d.model.model.Model.update`: additive, but for the rotation nodes, whose
        increment is a spin Δθ and whose ψ becomes log(exp(Δθ) exp(ψ)) (each node on its owner, no
        communication)."""
        if not self._spins:
            z[free] += dz
            return
        step = np.zeros(len(z))
        step[free] = dz
        for physics, places in self._spins:
            spin = step[places]
            step[places] = 0.0
            psi = z[places]
            moved = np.any(spin != 0.0, axis=1)          # the others keep their bits
            psi[moved] = physics.update(psi, spin)[moved]
            z[places] = psi
        z[free] += step[free]

    def norm(self, v):
        """The 2-norm of the distributed vector whose part on this rank is ``v``: the ranks' sums
        of squares added in rank order on every rank (the same number everywhere)."""
        v = np.asarray(v)
        return math.sqrt(math.fsum(self.comm.tompi4py().allgather(float(np.dot(v, v)))))

    def _vector(self, values):
        """A PETSc vector holding this rank's part ``values`` (a copy)."""
        v = self.load.duplicate()
        v.setArray(np.ascontiguousarray(values))
        return v

    def physical(self, z):
        """The PETSc vector of the physical components of the iterate whose part here is ``z``
        (``T z`` with clamps, :mod:`mortar1d3d.supports`)."""
        x = self._vector(z)
        if self.rotation is None:
            return x
        y = x.duplicate()
        self.rotation.mult(x, y)
        x.destroy()
        return y

    def ghosted(self, x):
        """The entries of the PETSc vector ``x`` that this rank's elements read (``physics.needed``),
        its own and the ghosts (collective)."""
        values = self._ghosts(x).copy()
        self.ghost_updates += 1
        return values

    def gather(self, v):
        """The vector whose part on this rank is ``v``, in the serial numbering on rank 0 (None on
        the others); for the Result, after the loop."""
        parts = self.comm.tompi4py().gather(np.asarray(v), root=0)
        return None if parts is None else np.concatenate(parts)[self.layout.of_serial]

    def scatter_from_root(self, v):
        """This rank's part of the vector ``v`` that rank 0 holds in the serial numbering (the
        inverse of :meth:`gather`; ``v`` is ignored on the other ranks)."""
        mpi = self.comm.tompi4py()
        parts = None
        if self.rank == 0:
            parts = [v[self.layout.owned_serial(r)] for r in range(mpi.Get_size())]
        return mpi.scatter(parts, root=0)

    def residual(self, z, t, tangent=True):
        """``r = f_int(z) + C z − t f_ext`` (this rank's part) and its Jacobian (PETSc)."""
        PETSc = petsc()
        failed = None
        x = self.physical(z)
        d = self.ghosted(x)
        try:
            (f_idx, f_val), K = self.physics.evaluate(d, tangent, t)
            states = [part.start(d) for part in self.rotational]
        except (FloatingPointError, ValueError, ArithmeticError) as exc:
            failed = str(exc)
        self._agree(failed, x)
        rows_of_G = []
        if self.rotational:
            # the rotational coupling: the line moments of the LM nodes (collective), then each
            # rank finishes its points (docs: mortar1d3d.distributed.rotational)
            moments = [part.exchange(state, d) for part, state in zip(self.rotational, states)]
            try:
                for part, state, lam in zip(self.rotational, states, moments):
                    (fi, fv), Kr, G = part.finish(state, lam, tangent)
                    f_idx, f_val = np.concatenate([f_idx, fi]), np.concatenate([f_val, fv])
                    if tangent:
                        K = tuple(np.concatenate([a, b]) for a, b in zip(K, Kr))
                    rows_of_G.append(G)
            except (FloatingPointError, ValueError, ArithmeticError) as exc:
                failed = str(exc)
            self._agree(failed, x)
        r = summed_vector(self.comm, f_idx, f_val, self.sizes)
        r.axpy(-t, self.load)
        if self.coupling is not None:
            r.axpy(1.0, self.coupling * x)
        twist = self._twist_residual(x, r, tangent) if self._twist_any else None
        x.destroy()
        if self.rotation is not None:
            physical, r = r, r.duplicate()
            self.rotation.multTranspose(physical, r)
            physical.destroy()
        self.last_residual = r.getArray().copy()
        r.destroy()
        if not tangent:
            return self.last_residual, None
        A = coo_matrix(self.comm, *K, self.sizes, self.sizes, block_size=self.solver.block_size)
        if self.coupling is not None:
            A.axpy(1.0, self.coupling, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        for part, G in zip(self.rotational, rows_of_G):
            Kr = part.tangent(G)
            if Kr is not None:
                A.axpy(1.0, Kr, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
                Kr.destroy()
        if twist is not None:
            A = self._twist_tangent(A, twist)
        if self.rotation is not None:
            physical, A = A, A.PtAP(self.rotation)
            physical.destroy()
        # the Newton loop holds one tangent at a time: the last one is freed now (as the KSP is)
        if self.last_tangent is not None:
            self.last_tangent.destroy()
        self.last_tangent = A
        return self.last_residual, A

    def _twist_residual(self, x, r, tangent):
        """The twist supports' change of variables on the residual (as ``Model._twist_jacobian``,
        each rank on the held triplets it owns): ``r ← Dᵀ r`` in place, D the identity but for the
        left Jacobian T(ψ) on those triplets. Returns their blocks (T, E) for :meth:`_twist_tangent`."""
        from ..model.model import twist_blocks
        blocks = twist_blocks(x.getArray(), r.getArray(), self._twist, tangent)
        values = r.getArray().copy()
        for s, (T, _) in zip(self._twist, blocks):
            values[s:s + 3] = T.reshape(3, 3).T @ values[s:s + 3]
        r.setArray(values)
        return blocks

    def _twist_tangent(self, A, blocks):
        """``Dᵀ A D + E`` (``Model._twist_jacobian``) of the twist supports' blocks (collective)."""
        PETSc = petsc()
        first = int(self.layout.ranges[self.rank])
        keep = np.ones(self.sizes[0], dtype=bool)
        rows, cols, D_vals, E_vals = [], [], [], []
        for s, (T, E) in zip(self._twist, blocks):
            keep[s:s + 3] = False
            rows.append(first + np.repeat(np.arange(s, s + 3), 3)), cols.append(first + np.tile(np.arange(s, s + 3), 3))
            D_vals.append(T), E_vals.append(E)
        diagonal = first + np.flatnonzero(keep)
        D = coo_matrix(self.comm, np.concatenate([diagonal] + rows), np.concatenate([diagonal] + cols),
                       np.concatenate([np.ones(len(diagonal))] + D_vals), self.sizes, self.sizes)
        E = coo_matrix(self.comm, _cat(rows, np.int64), _cat(cols, np.int64), _cat(E_vals, float), self.sizes,
                       self.sizes)
        physical, A = A, A.PtAP(D)
        A.axpy(1.0, E, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        for m in (physical, D, E):
            m.destroy()
        return A

    def _agree(self, failed, x):
        """One rank's failure is every rank's (the Newton loop must take the same branch everywhere):
        raises ArithmeticError on every rank if ``failed`` (a message or None) is set on any."""
        messages = [m for m in self.comm.tompi4py().allgather(failed) if m]
        if messages:
            x.destroy()
            raise ArithmeticError(messages[0])

    def free_block(self, K):
        """The tangent on the free unknowns: ``K`` itself (the supports are removed in :meth:`solve_linear`)."""
        return K

    def product(self, K, v, absolute=False):
        """``K v`` (``|K| v`` with ``absolute``), this rank's part of each."""
        x = self._vector(v)
        if absolute:
            # |K|: the same rows with the absolute values (global column indices)
            indptr, indices, data = K.getValuesCSR()
            K = petsc().Mat().createAIJ(size=K.getSizes(), csr=(indptr, indices, np.abs(data)), comm=self.comm)
        y = K * x
        out = y.getArray().copy()
        for w in (x, y) + ((K,) if absolute else ()):
            w.destroy()
        return out

    def solve_linear(self, K, b, x0=None, rtol=None):
        """The increment on the free unknowns: ``K_ff x = b`` (``b`` on this rank's free unknowns)."""
        rtol = self.model.scene.analysis["rtol"] if rtol is None else rtol
        full = np.zeros(self.sizes[0])
        full[self.free] = b
        rhs = self._vector(full)
        # the supports: rows and columns of the fixed unknowns become the identity, their entries of
        # the right side are zero already (the increment keeps the prescribed values); on a copy, since
        # the caller still needs K (the linear step's residual r0 + K (z - z0), the reactions)
        K = K.duplicate(copy=True)
        if len(self.dropped):
            # the left-out multipliers' rows have no diagonal entry (a zero block), which
            # MatZeroRowsColumns needs: an explicit zero there first
            PETSc = petsc()
            K.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
            for row in self.dropped_rows:
                K.setValue(row, row, 0.0, addv=PETSc.InsertMode.ADD_VALUES)
            K.assemble()
        K.zeroRowsColumns(self.fixed_rows.astype(petsc().IntType), diag=1.0)
        x = rhs.duplicate()
        try:
            self.last_linear_info = info = self.solver.solve(K, rhs, x, rtol)
            totals = self.linear_totals
            totals["solves"] += 1
            for key in ("iterations", "setup_seconds", "solve_seconds"):
                totals[key] += info.get(key, 0)
        finally:
            K.destroy()         # the copy (see LinearSolver.solve: freed now, not by the garbage collector)
        out = x.getArray()[self.free].copy()
        x.destroy(), rhs.destroy()
        return out
