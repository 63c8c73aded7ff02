"""The rotational coupling of ``simo_reissner`` beams (``coupling.rotational``) on PETSc.

Each rank evaluates the coupling of its owned beam elements with the serial
:class:`~mortar1d3d.physics.rotational_coupling.RotationalCoupling` on its small meshes (the
integration points of its positional coupling, the solid elements they reach, the owned beam
elements with their serial reference triads): the same Numba kernels per point, in every Newton
iteration (the coupling is state dependent). What crosses ranks is a rotational LM node at a beam
node whose elements live on two ranks: its sums over the points (κ_j, the weighted gap g_j, the
rows G_j of the linearisation) have parts on both. The LM nodes are numbered rank by rank like the
positional ones (:func:`~.numbering.lm_renumbering`, with ``coupling.rotational.lm``), and:

* penalty (mortar constraint): each rank adds its parts of g into a PETSc vector over the LM rows,
  the owner forms the line moments λ_j = ε κ_j⁻¹ g_j, one ``VecScatter`` brings each rank the λ_j
  of its LM nodes, and the rank finishes its points with them (forces Σ_p w_p J_pᵀ λ_p and the
  geometric part λᵀ ∂²g, summed by PETSc's assembly); the tangent's ε Gᵀ κ⁻¹ G is formed by PETSc
  from the distributed G (``MatTransposeMatMult``, every iteration);
* penalty at the Gauss points (``constraint = "gauss_point"``): every row is one point, so each
  rank's part is complete;
* Lagrange multipliers: the rotational multipliers (three per coupled LM node, κ_j > 0) follow the
  positional ones in the serial order and are owned by the rank of their LM node, after its
  displacements (:meth:`~.solve.SystemLayout.with_multipliers`); a rank reads the multipliers of
  its LM nodes with its ghosts and adds its parts of g (the constraint rows of the residual), of
  G, Gᵀ and λᵀ ∂²g into the system.

κ is summed once and gathered on every rank (one value per LM node, as the positional κ).
"""
import numpy as np

from .assemble import serial_lm_nodes
from .numbering import lm_renumbering
from .petsc import Entries, coo_matrix, gather_vector, petsc, summed_vector
from .system import owned_beam_physics

_EMPTY = (np.zeros(0, np.int64), np.zeros(0))
_NO_ENTRIES = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))


def rotational_parts(model, ops, part, numbering, comm):
    """One :class:`RotationalPart` per beam group with rotations (collective), and the owner rank of
    every rotational multiplier in the serial order (empty for penalty)."""
    rot = model.scene.coupling.get("rotational") if model.scene.coupled else None
    if rot is None:
        return [], np.zeros(0, np.int64)
    parts, owners = [], []
    for k, g in enumerate(model.groups):
        if g.rotations.size:
            parts.append(RotationalPart(model, k, ops[k].local, part, numbering, comm))
            owners.append(parts[-1].multiplier_owner)
    return parts, (np.concatenate(owners) if owners else np.zeros(0, np.int64))


def _penalty(model, group, comm, local_max):
    """ε of ``coupling.rotational`` as the serial model takes it: the scene's, or the default
    factor × the largest GI_T of the group's elements (a maximum over the ranks) over the squared
    mean element length."""
    from ..physics.rotational_coupling import DEFAULT_PENALTY_FACTOR
    given = model.scene.coupling["rotational"]["penalty"]
    if given is not None:
        return given
    from mpi4py import MPI
    largest = comm.tompi4py().allreduce(local_max, op=MPI.MAX)
    return DEFAULT_PENALTY_FACTOR * float(largest) / float(np.mean(group.mesh.lengths)) ** 2


class RotationalPart:
    """The rotational coupling of beam group ``k`` on this rank (see the module docstring).

    Collective construction; :meth:`bind` then places it in the system's layout and the unknowns
    this rank reads. Per evaluation: :meth:`start` (local), :meth:`exchange` (collective),
    :meth:`finish` (local), :meth:`tangent` (collective).

    Attributes
    ----------
    multiplier_owner : (m,) int64
        Lagrange: the rank of each of the group's rotational multipliers (serial order); empty
        for penalty.
    """

    def __init__(self, model, k, local, part, numbering, comm):
        from ..physics.rotational_coupling import RotationalCoupling
        rot = model.scene.coupling["rotational"]
        g = model.groups[k]
        self.comm, self.rank = comm, comm.getRank()
        self.enforcement, self.gauss_point = rot["enforcement"], rot["constraint"] == "gauss_point"
        self.fourc = rot["forces"] == "fourc"
        self.lm = lm_renumbering(numbering.beams[k].owner, part.beam_part[k], rot["lm"], part.n_parts)
        owned = part.owned_beams(self.rank, k)
        _, _, beam, rotation_nodes = owned_beam_physics(model, k, owned)
        penalty = _penalty(model, g, comm, float(beam.CM[:, 0].max()) if beam is not None else -np.inf)
        self.rc, self.lm_new = None, np.zeros(0, np.int64)
        kappa_local = np.zeros(0)
        if beam is not None and local.ops is not None:
            n_solid = 3 * local.solid.n_nodes
            self.rc = RotationalCoupling(local.ops, beam, local.solid, n_solid, n_solid + 3 * beam.n_rotation_nodes,
                                         triad=rot["triad"], penalty=penalty, lm=rot["lm"],
                                         enforcement=rot["enforcement"], constraint=rot["constraint"],
                                         forces=rot["forces"])
            # the local unknowns of the coupling: the reached solid nodes' DOFs, then the rotation nodes'
            self.columns = np.concatenate([(3 * local.solid_nodes[:, None] + np.arange(3)).ravel(),
                                           g.rotations.dofs(rotation_nodes, [0, 1, 2])])
            self.lm_new = self.lm.new_of_old[serial_lm_nodes(local.beams, local.beam_nodes, owned, g.mesh.n_nodes,
                                                             rot["lm"])]
            kappa_local = self.rc.kappa
        # κ of every LM node, summed over the ranks (rank-major), and the serial rule for the coupled nodes
        kappa = summed_vector(comm, self.lm_new, kappa_local, (self.lm.count(self.rank), self.lm.n))
        self.kappa = gather_vector(kappa)
        kappa.destroy()
        coupled = self.kappa > 0          # as RotationalCoupling: κ_j > 0 carries a moment or a multiplier
        #: ε / κ_j of every rank-major LM row (zero where κ_j ≤ 0)
        self.weight = np.zeros(3 * self.lm.n)
        self.weight[np.repeat(coupled, 3)] = penalty / np.repeat(self.kappa[coupled], 3)
        self.multiplier_owner = np.zeros(0, np.int64)
        if self.enforcement == "lagrange":
            serial_coupled = np.flatnonzero(np.repeat(coupled[self.lm.new_of_old], 3))   # serial LM rows
            # the group's multipliers in the serial order: its coupled rows; their place among them
            self.multiplier_of_row = np.full(3 * self.lm.n, -1, dtype=np.int64)         # rank-major row -> index
            self.multiplier_of_row[self.lm.dofs(serial_coupled, 3)] = np.arange(len(serial_coupled))
            self.multiplier_owner = self.lm.owner[serial_coupled // 3]
        self.rows = (3 * self.lm_new[:, None] + np.arange(3)).ravel()       # rank-major rows of the local LM rows
        self._moments = None

    def bind(self, layout, physics, first_multiplier):
        """Places this part in the system: ``layout`` of all unknowns, the owned physics whose
        evaluation reads what it reads (:meth:`~.system.OwnedPhysics.read_also` first with
        :meth:`reads`), and the serial index of the group's first multiplier (Lagrange)."""
        rank = self.rank
        self.system_sizes = (int(layout.ranges[rank + 1] - layout.ranges[rank]), int(layout.ranges[-1]))
        self.row_sizes = (3 * self.lm.count(rank), 3 * self.lm.n)
        self.first_multiplier = first_multiplier
        if self.rc is not None:
            self.system_columns = layout.of_serial[self.columns]
            self.places = physics.place(self.columns)
            if self.enforcement == "lagrange":
                mult = self.multiplier_of_row[self.rows]
                self.coupled_local = np.flatnonzero(mult >= 0)
                serial = first_multiplier + mult[self.coupled_local]
                self.multiplier_places = physics.place(serial)
                self.multiplier_system = layout.of_serial[serial]
        if self.enforcement == "penalty" and not self.gauss_point:
            # the line moments of this rank's LM rows, from their owners (one VecScatter)
            g = summed_vector(self.comm, *_EMPTY, self.row_sizes)
            self._moments = (g, Entries(g, self.rows))

    def reads(self, first_multiplier):
        """The serial unknowns this part reads (collective with :meth:`bind` in the same order)."""
        if self.rc is None:
            return np.zeros(0, np.int64)
        out = [self.columns]
        if self.enforcement == "lagrange":
            mult = self.multiplier_of_row[self.rows]
            out.append(first_multiplier + mult[mult >= 0])
        return np.concatenate(out)

    @property
    def n_multipliers(self):
        return len(self.multiplier_owner)

    # -- evaluation ------------------------------------------------------------------------------
    def start(self, d):
        """The local point state at the ghosted unknowns ``d`` (:attr:`~.system.OwnedPhysics.needed`
        order), or None without local points."""
        if self.rc is None:
            return None
        x = d[self.places]
        n_solid = self.rc.rotation_offset
        return self.rc.point_state(x[:n_solid], x[n_solid:].reshape(-1, 3))

    def exchange(self, state, d):
        """The line moments λ_j (n_lm_local, 3) of the local LM rows (collective for the penalty
        of the mortar constraint)."""
        if self._moments is not None:
            g, entries = self._moments
            g.set(0.0)
            if state is not None:
                PETSc = petsc()
                g.setValues(self.rows.astype(PETSc.IntType), state[-1].ravel(), addv=PETSc.InsertMode.ADD_VALUES)
            g.assemblyBegin()
            g.assemblyEnd()
            first = 3 * int(self.lm.ranges[self.rank])
            g.setArray(g.getArray() * self.weight[first: first + self.row_sizes[0]])
            lam = entries(g).copy()
            return None if state is None else lam.reshape(-1, 3)
        if state is None:
            return None
        if self.enforcement == "lagrange":
            lam = np.zeros(len(self.rows))
            lam[self.coupled_local] = d[self.multiplier_places]
            return lam.reshape(-1, 3)
        # the Gauss-point penalty: every row is a point of this rank
        return self.rc.penalty * self.rc.rows_kappa_inverse[:, None] * state[-1]

    def finish(self, state, lam, tangent):
        """This rank's forces (system index, values), tangent triplets, and for the penalty of the
        mortar constraint the local rows of G (and of the forces' G, fourc) for :meth:`tangent`."""
        if state is None:
            return _EMPTY, _NO_ENTRIES, None
        g, r, Gm, K_lam, Gf = self.rc.linearised(state, lam, tangent)
        cols = self.system_columns
        f_idx, f_val = [cols], [r]
        if self.enforcement == "lagrange":
            # the constraint rows of the residual: this rank's part of g at the coupled LM rows
            f_idx.append(self.multiplier_system), f_val.append(g.ravel()[self.coupled_local])
        forces = (np.concatenate(f_idx), np.concatenate(f_val))
        if not tangent:
            return forces, None, None
        rows, cc, vals, G = [], [], [], None
        if self.enforcement == "lagrange":
            Gc = Gm[self.coupled_local].tocoo()
            K_lam = K_lam.tocoo()
            rows += [cols[K_lam.row], self.multiplier_system[Gc.row], cols[Gc.col]]
            cc += [cols[K_lam.col], cols[Gc.col], self.multiplier_system[Gc.row]]
            vals += [K_lam.data, Gc.data, Gc.data]
        elif self.gauss_point:
            K = self.rc.penalty_tangent(Gm, K_lam, Gf).tocoo()
            rows, cc, vals = [cols[K.row]], [cols[K.col]], [K.data]
        else:
            K_lam = K_lam.tocoo()
            rows, cc, vals = [cols[K_lam.row]], [cols[K_lam.col]], [K_lam.data]
            G = [self._rows_of(Gm)] + ([] if Gf is Gm else [self._rows_of(Gf)])
        return forces, (np.concatenate(rows), np.concatenate(cc), np.concatenate(vals)), G

    def _rows_of(self, G):
        G = G.tocoo()
        return self.rows[G.row], self.system_columns[G.col], G.data

    def tangent(self, G):
        """ε Gᵀ κ⁻¹ G (fourc: ε G_fᵀ κ⁻¹ G) of the mortar constraint's penalty, formed by PETSc
        from every rank's rows of G (collective; None for the other enforcements)."""
        if self._moments is None:
            return None
        parts = G if G is not None else [_NO_ENTRIES]
        Gm = coo_matrix(self.comm, *parts[0], self.row_sizes, self.system_sizes)
        weighted = Gm.copy()
        w = weighted.createVecLeft()
        first = 3 * int(self.lm.ranges[self.rank])
        w.setArray(self.weight[first: first + self.row_sizes[0]])
        weighted.diagonalScale(L=w)
        # (decided by the scene, the same on every rank: a collective call or none)
        left = coo_matrix(self.comm, *(parts[1] if len(parts) > 1 else _NO_ENTRIES), self.row_sizes,
                          self.system_sizes) if self.fourc else Gm
        K = left.transposeMatMult(weighted)
        for m in {id(x): x for x in (Gm, weighted, left, w)}.values():
            m.destroy()
        return K

    def close(self):
        if self._moments is not None:
            g, entries = self._moments
            entries.scatter.destroy(), entries.values.destroy(), g.destroy()
            self._moments = None

