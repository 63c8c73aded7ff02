"""The Model: the physics of a built scene, and nothing else.

A :class:`Model` takes what :func:`~mortar1d3d.model.build.build` made of a scene (meshes, beam
groups, named sets, the DOF map) and adds the physics: prescribed values and supports, loads,
the solid and beam models, the coupling (after :meth:`Model.prepare`), and the nonlinear system
that :mod:`mortar1d3d.solvers.newton` solves (``fixed``, ``free``, ``prescribed``, ``residual``,
``solve_linear``). Global unknowns follow the DOF map (:mod:`.dofmap`): solid displacements,
the centreline DOFs of each beam group (Hermite ``[r, t]`` per node for ``torsion_free``,
positions for ``truss``), rotations (the total spatial rotation vectors ψ of the rotation nodes
of ``simo_reissner`` groups), then Lagrange multipliers (coupled LM rows) when the coupling is
enforced with Lagrange multipliers, followed by the rotational coupling's multipliers (per group,
coupled rotational LM nodes × 3) when ``coupling.rotational.enforcement = "lagrange"``. Rotations are updated multiplicatively (:meth:`Model.update`):
the residual and tangent are taken with respect to spatial spins, so a Newton increment of a
rotation node is a spin Δθ and ψ ← log(exp(Δθ) exp(ψ)).

Every stage that does work increments ``Model.counts[<effect>]`` with the names that
:func:`~mortar1d3d.model.plan` lists, so that tests can prove what ran.
"""
import warnings
from collections import Counter

import numpy as np
import scipy.sparse as sp

from ..errors import AccuracyWarning, CouplingWarning, format_ids
from ..mortar.assemble import assemble_mortar
from ..scene import Scene, SceneError
from ..supports import RotatedBasis, clamp_frame
from . import checks
from .tangent import FilledBlock, TangentPattern
from .build import BuiltScene, build

DEFAULT_PENALTY_FACTOR = 1e3     # ε = 1e3 E_solid when the scene gives no penalty
PENALTY_ROUNDOFF_LIMIT = 1e8     # ε / E_solid above which round-off beats the penalty error (AccuracyWarning)


def twist_blocks(d, r, starts, tangent):
    """The blocks of the twist supports' change of variables (:meth:`Model._twist_jacobian`) at
    the rotation triplets starting at ``starts`` of ``d`` (total rotation vectors ψ) and ``r``
    (their residual in spins): per triplet ``T(ψ)`` (the left Jacobian, δθ = T δψ) and, with
    ``tangent``, ``E`` with ``E[:, j] = (∂T/∂ψ_j)ᵀ r``, each as 9 values row by row (E None
    without ``tangent``)."""
    from ..physics.rotations import jacobian, jacobian_derivative_transpose
    T, E, work = np.empty((3, 3)), np.empty((3, 3)), np.empty(9)
    out = []
    for s in starts:
        psi = np.ascontiguousarray(d[s:s + 3])
        jacobian(psi, T)
        if tangent:
            u, col = np.ascontiguousarray(r[s:s + 3]), np.empty(3)
            for j in range(3):
                jacobian_derivative_transpose(psi, np.eye(3)[j], u, col, work)
                E[:, j] = col
        out.append((T.ravel().copy(), E.ravel().copy() if tangent else None))
    return out


class Model:
    """The physics of a built scene: supports, loads, solid and beam models, coupling.

    Parameters
    ----------
    built : BuiltScene or Scene
        What :func:`~mortar1d3d.model.build.build` made of a scene. A :class:`Scene` is built
        first (a convenience: ``Model(scene)`` is ``Model(build(scene))``).

    Construction is cheap (meshes, sets, prescribed values); :meth:`prepare` assembles what the
    scene needs. ``counts`` records every stage that ran.
    """

    #: a nonlinear analysis keeps the AMG set-up of one tangent for the next Newton iterations
    #: (:class:`~mortar1d3d.solvers.reuse.ReusedPreconditioner`); False builds one per solve
    reuse_preconditioner = True

    def __init__(self, built):
        if isinstance(built, Scene):
            built = build(built)
        elif not isinstance(built, BuiltScene):
            raise TypeError(f"expected a Scene, got {type(built).__name__}")
        scene = built.scene
        self.scene = scene
        self.counts = Counter()
        self._tangent_pattern = None
        self._border = None
        self.linear = scene.analysis["kinematics"] == "linear"
        self.solid_mesh = built.solid_mesh
        self.n_solid_nodes = self.solid_mesh.n_nodes if self.solid_mesh is not None else 0
        self.groups, self.entry_group = built.groups, built.entry_group
        self.sets = built.sets
        self.dofmap = built.dofmap
        self.n_displacement_dofs = self.dofmap.n_displacement
        self.n_multipliers = 0
        c = scene.coupling
        self.penalty = None
        if scene.coupled:
            self.penalty = c["penalty"] if c["penalty"] is not None else DEFAULT_PENALTY_FACTOR * scene.solid["material"]["E"]
            ratio = self.penalty / scene.solid["material"]["E"]
            if c["enforcement"] == "penalty" and ratio > PENALTY_ROUNDOFF_LIMIT:
                # the penalty error falls like E/ε, the round-off of the penalty terms grows like
                # eps_mach ε/E: past ~1/sqrt(eps_mach) the result gets worse, not better
                # (tests/test_solver_stress.py: best at 1e6 E, 2 % error at 1e12 E)
                warnings.warn(f"coupling.penalty: {self.penalty:.3g} is {ratio:.1e} × solid.material.E; above "
                              f"{PENALTY_ROUNDOFF_LIMIT:.0e} × E round-off of the penalty terms costs accuracy "
                              "(about machine epsilon × penalty / E relative). Use 1e2..1e6 × E, or "
                              "enforcement = \"lagrange\"", AccuracyWarning, stacklevel=3)
        self._check_solver()
        self.fixed_dofs, self.fixed_values, self.dirichlet_dofs, self.basis = self._dirichlet()
        # every set is resolved here, so that plan() reports what solve() would
        self.load_sets = self._load_sets()
        families = scene.solid["material"].get("fibres", ()) if self.solid_mesh is not None else ()
        self.fibre_regions = self.sets.fibre_regions(families)
        self.prepared = False
        self._follow = None          # auxiliary-space split, built on first use (_follow_split)
        self._preconditioner = None  # ReusedPreconditioner of a nonlinear analysis (_solve_reusing)

    # -- sets -----------------------------------------------------------------------------------
    def select(self, spec, path):
        """Resolve a set spec to ``("solid", node ids)`` or ``("beam", group, node ids)``
        (:meth:`~.sets.NamedSets.select`)."""
        return self.sets.select(spec, path)

    def _set_dofs(self, sel, components):
        """Unknowns of ``components`` at the nodes of a resolved set ``sel``."""
        block = self.dofmap.solid if sel[0] == "solid" else sel[1].dofs
        return block.dofs(sel[-1], components)

    @staticmethod
    def _rotation_dofs(sel):
        """Rotation unknowns (three per node) at the mesh nodes of a resolved beam set ``sel``
        (a mesh node is the rotation node of the same index)."""
        return sel[1].rotations.dofs(sel[2], [0, 1, 2])

    def _dirichlet(self):
        """Fixed DOFs and their values in the basis of the unknowns, the position DOFs of each entry
        (for its reaction), and that basis (:class:`~mortar1d3d.supports.RotatedBasis` of the clamps)."""
        dofs, values, per_entry = [], [], []
        clamps = {}
        whole, self.twist_starts = {}, np.zeros(0, np.int64)    # rotation triplets: fixed whole / their twist held
        for i, d in enumerate(self.scene.dirichlet):
            sel = self.select(d["on"], f"dirichlet[{i}].on")
            if d.get("twist"):
                starts, frames = self._twist_frames(sel, f"dirichlet[{i}].twist")
                clamps.update(zip(starts.tolist(), frames))
                self.twist_starts = np.union1d(self.twist_starts, starts)
                dofs.append(starts + 2)                 # the component along the reference tangent
                values.append(np.zeros(len(starts)))
            idx = self._set_dofs(sel, d["components"])
            val = np.tile(d["value"][d["components"]], len(idx) // max(len(d["components"]), 1))
            dofs.append(idx)
            values.append(val)
            if d["clamp"]:
                g = sel[1]
                if not g.type.element.has_tangents:
                    raise SceneError(f"dirichlet[{i}].clamp: beam {d['on']!r} has no tangent DOFs ({g.model})")
                starts, frames = self._clamp_frames(g, sel[2])
                clamps.update(zip(starts.tolist(), frames))
                t_idx = (starts[:, None] + np.arange(2)).ravel()      # e1·Δt, e2·Δt in the rotated frame
                dofs.append(t_idx)
                values.append(np.zeros(len(t_idx)))
            if d["rotation"] is not None or (d["clamp"] and sel[1].rotations.size):
                # the total rotation vector of every node of the set (a clamp: the reference triad)
                r_idx = self._rotation_dofs(sel)
                whole.update((int(x), i) for x in r_idx[::3])
                rotation = d["rotation"] if d["rotation"] is not None else np.zeros(3)
                dofs.append(r_idx)
                values.append(np.tile(rotation, len(r_idx) // 3))
            per_entry.append(idx)     # position DOFs only: their reactions are forces
        both = [x for x in self.twist_starts.tolist() if x in whole]
        if both:
            raise SceneError(f"dirichlet[{whole[both[0]]}]: prescribes the whole rotation of a node whose twist another "
                             "entry holds (twist = true); give one of them per node")
        starts = sorted(clamps)
        basis = RotatedBasis(starts, [clamps[s] for s in starts])
        if not dofs:
            return np.zeros(0, np.int64), np.zeros(0), per_entry, basis
        dofs, values = np.concatenate(dofs), np.concatenate(values)
        order = np.argsort(dofs, kind="stable")
        dofs, values = dofs[order], values[order]
        same = dofs[1:] == dofs[:-1]
        if same.any():
            clash = same & (values[1:] != values[:-1])
            if clash.any():
                raise SceneError(f"dirichlet: DOFs {format_ids(dofs[1:][clash])} are prescribed twice with "
                                 "different values")
            keep = np.concatenate([[True], ~same])
            dofs, values = dofs[keep], values[keep]
        return dofs, values, per_entry, basis

    def _twist_frames(self, sel, path):
        """First rotation unknown of each node of a beam set and its frame ``(e1, e2, t0)`` (rows;
        ``t0`` the node's unit reference tangent): the twist support holds the third component.

        The rotation unknowns of these nodes are the total rotation vectors in that frame, updated
        additively (see :meth:`update` and :meth:`_twist_jacobian`), so that ``t0·ψ = 0`` holds
        exactly in every iteration.
        """
        g = sel[1]
        if not g.rotations.size:
            raise SceneError(f"{path}: beam set has no rotation DOFs ({g.model})")
        nodes = np.asarray(sel[2], dtype=np.int64)
        return g.rotations.dofs(nodes, [0]), [clamp_frame(g.mesh.tangents[node]) for node in nodes]

    def _twist_jacobian(self, d, r, K):
        """Residual and Jacobian with the rotation unknowns of twist-held nodes as total rotation
        vectors ψ (additive) instead of spins: ``δθ = T(ψ) δψ`` (left Jacobian), so ``r ← Dᵀ r`` and
        ``K ← Dᵀ K D + E`` with ``D`` the identity but for ``T(ψ)`` on those triplets and
        ``E[:, j] = (∂T/∂ψ_j)ᵀ r`` on their diagonal blocks (the rows' own dependence on ψ)."""
        n_all = len(r)
        rows, cols, vals = [np.arange(n_all)], [np.arange(n_all)], [np.ones(n_all)]
        keep = np.ones(n_all, dtype=bool)
        extra = []
        for s, (T, E) in zip(self.twist_starts, twist_blocks(d, r, self.twist_starts, K is not None)):
            keep[s:s + 3] = False
            block = (np.repeat(np.arange(s, s + 3), 3), np.tile(np.arange(s, s + 3), 3))
            rows.append(block[0])
            cols.append(block[1])
            vals.append(T)
            if K is not None:
                extra.append((block, E))
        rows[0], cols[0], vals[0] = rows[0][keep], cols[0][keep], vals[0][keep]
        D = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_all, n_all))
        if K is not None:
            K = D.T @ K @ D
            for (i, j), v in extra:
                K = K + sp.csr_matrix((v, (i, j)), shape=K.shape)
            K = K.tocsr()
        return D.T @ r, K

    @staticmethod
    def _clamp_frames(g, nodes):
        """First tangent DOF of each clamped node and its frame ``(e1, e2, t0)``.

        At a Hermite node the tangent's length is the local stretch: a clamp fixes only its
        direction, the components along ``e1`` and ``e2`` (see :mod:`mortar1d3d.supports`), so
        that a clamped beam behaves the same in every orientation.
        """
        starts = g.dofs.dofs(nodes, [3])                # a Hermite node's block: [r, t]
        return starts, [clamp_frame(g.mesh.tangents[node]) for node in nodes]

    def _check_solver(self):
        solver, enforcement = self.scene.analysis["solver"], self.scene.coupling["enforcement"]
        lagrange = self.scene.coupled and enforcement == "lagrange"
        if solver == "block" and not lagrange:
            raise SceneError("analysis.solver: 'block' is the saddle-point solver of Lagrange-multiplier coupling; "
                             "use 'auto', 'direct' or 'amg'")
        framed = [g.model for g in self.groups if not g.type.symmetric_tangent]
        if framed and solver in ("amg", "block") and not self.linear:
            raise SceneError(f"analysis.solver: {solver!r} runs CG or MINRES, which need a symmetric tangent; the "
                             f"{framed[0]} beam's tangent is not symmetric away from its reference state, so a "
                             "nonlinear analysis with it uses 'direct' (or 'auto', which picks it)")
        rot = self.scene.coupling.get("rotational") if self.scene.coupled else None
        if rot is not None and rot["enforcement"] == "lagrange" and solver in ("amg", "block"):
            raise SceneError(f"analysis.solver: {solver!r} is not implemented with coupling.rotational.enforcement = "
                             "\"lagrange\" (its constraint rows act on rotations, which the block preconditioner does "
                             "not know); use 'direct' or 'auto' (which picks it), or enforcement = \"penalty\"")
        if solver == "amg" and lagrange:
            raise SceneError("analysis.solver: Lagrange-multiplier coupling gives a saddle point; use 'auto', "
                             "'direct' or 'block' (GMRES, the auxiliary-space AMG inside a block preconditioner)")

    # -- solver choice --------------------------------------------------------------------------
    @property
    def lagrange(self):
        return self.scene.coupled and self.scene.coupling["enforcement"] == "lagrange"

    def linear_solver_method(self, n_unknowns=None):
        """The linear solver that ``analysis.solver`` resolves to for this model."""
        solver = self.scene.analysis["solver"]
        if solver != "auto":
            return solver
        from ..solvers.direct import DIRECT_MAX_DOFS
        if self.rotational_lagrange:
            return "direct"         # the only solver of rotational multipliers (see _check_solver)
        n = self.n_displacement_dofs if n_unknowns is None else n_unknowns
        if n <= DIRECT_MAX_DOFS:
            return "direct"
        if not self.linear and any(not g.type.symmetric_tangent for g in self.groups):
            # beams with rotations or 4C's beam3eb: a non-symmetric tangent, which CG and MINRES do not take
            return "direct"
        return "block" if self.lagrange else "amg"

    # -- operators ------------------------------------------------------------------------------
    def prepare(self, operators=None):
        """Assemble everything that is constant: mortar operators, coupling, dead loads; check supports.

        Parameters
        ----------
        operators : sequence of MortarOperators, optional
            Precomputed mortar operators, one per beam group (group order, see ``groups``), for
            this scene's meshes and ``coupling.lm``: they are used instead of calling
            :func:`~mortar1d3d.assemble_mortar` (no ``mortar.*`` counts). For callers that
            already hold the operators, e.g. the trade-off study, which solves one scene with
            the operators of several integration variants. Default: assemble them.

        Returns
        -------
        self
        """
        if self.prepared:
            return self
        if operators is not None:
            operators = self._check_operators(operators)
        from ..physics.coupling import Coupling
        from ..physics.materials import material
        from ..physics.solid import SolidModel
        sc = self.scene
        n = self.n_displacement_dofs
        if self.solid_mesh is not None:
            mat = sc.solid["material"]
            try:
                self.solid_physics = SolidModel(self.solid_mesh, material(mat["model"], mat["E"], mat["nu"]),
                                                kinematics="linear" if self.linear else "nonlinear",
                                                fibres=self._fibre_field(mat.get("fibres", ())))
            except ValueError as exc:
                raise SceneError(f"solid.material: {exc}") from None
        for g in self.groups:
            sections = [(b - a, sc.beams[i]["section"]) for i, (a, b) in zip(g.entries, g.entry_elements)]
            g.physics = g.type.make_physics(g.mesh, sections, g.triads,
                                            [sc.beams[i].get("force_rule") for i in g.entries],
                                            [sc.beams[i].get("virtual_spins") for i in g.entries])
            if g.rotations.size:
                self.counts["beam.rotations"] += 1
        if sc.coupled:
            c = sc.coupling
            for k, g in enumerate(self.groups):
                if operators is not None:
                    g.operators = operators[k]
                else:
                    g.operators = assemble_mortar(g.mesh, self.solid_mesh, integration=c["integration"],
                                                  n_gauss=c["n_gauss"], lm=c["lm"], search_points=c["search_points"])
                    self.counts["mortar.search"] += 1
                    if c["integration"] in ("segment", "auto", "element_boundary"):
                        self.counts["mortar.segmentation"] += 1
                    self.counts["mortar.integration_points"] += 1
                    self.counts["mortar.assembly"] += 1
                g.coupling = Coupling(g.operators, g.mesh, self.solid_mesh, g.dof_offset, n,
                                      constraint=c["constraint"], enforcement=c["enforcement"], penalty=self.penalty,
                                      negative_kappa=c.get("negative_kappa", "drop"))
                self.counts["coupling.lagrange" if self.lagrange else f"coupling.{c['constraint']}_penalty"] += 1
                self._check_coupled_lengths(g)
            self._prepare_rotational()
            if self.lagrange:
                self.constraint_matrix = sp.vstack([g.coupling.constraint_matrix() for g in self.groups], format="csr")
                self.n_multipliers = self.constraint_matrix.shape[0]
            else:
                K = self.groups[0].coupling.K
                for g in self.groups[1:]:
                    K = K + g.coupling.K
                self.coupling_stiffness = K.tocsr()
            # rotational multipliers follow the positional ones, group by group
            self.n_multipliers += sum(g.rotational.n_multipliers for g in self.groups if g.rotational is not None)
        self._prepare_loads()
        self.dofmap = self.dofmap.with_multipliers(self.n_multipliers)
        self.n_unknowns = self.dofmap.n_unknowns
        self.free = np.setdiff1d(np.arange(self.n_unknowns), self.fixed_dofs)
        self.fixed = self.fixed_dofs
        self.check_supports()
        self.prepared = True
        return self

    #: a beam whose coupled length falls short of its length by more than this fraction gets a
    #: CouplingWarning (the quadrature of the speed over the segments is far more accurate than this)
    UNCOUPLED_FRACTION_LIMIT = 1e-3

    def _check_coupled_lengths(self, g):
        """Record every beam's coupled (embedded) length and warn about beams partly or wholly outside.

        The coupled length of a beam is the sum of its integration points' weights (each includes
        ``|r0'|``), i.e. the length the coupling integrates over; ``coupled_length[i]`` and
        ``beam_length[i]`` are indexed like ``scene.beams``.
        """
        n_beams = len(self.scene.beams)
        if getattr(self, "coupled_length", None) is None:
            self.coupled_length, self.beam_length = np.zeros(n_beams), np.zeros(n_beams)
        per_element = np.bincount(g.operators.point_fields["beam_element"], g.operators.point_fields["weight"],
                                  minlength=g.mesh.n_elements)
        for entry, (a, b) in zip(g.entries, g.entry_elements):
            coupled, total = float(per_element[a:b].sum()), float(g.mesh.lengths[a:b].sum())
            self.coupled_length[entry], self.beam_length[entry] = coupled, total
            if coupled == 0.0:
                warnings.warn(f"beams[{entry}]: no part of this beam lies inside the solid, so it is not "
                              "coupled (check the units: a mm/m mix-up moves a beam out of the solid)",
                              CouplingWarning, stacklevel=4)
            elif coupled < (1.0 - self.UNCOUPLED_FRACTION_LIMIT) * total:
                warnings.warn(f"beams[{entry}]: {1.0 - coupled / total:.1%} of this beam ({total - coupled:.4g} of "
                              f"length {total:.4g}) lies outside the solid and is not coupled there",
                              CouplingWarning, stacklevel=4)

    def _prepare_rotational(self):
        """Rotational coupling (``coupling.rotational``) of every group with rotations."""
        rot = self.scene.coupling["rotational"]
        if rot is None:
            return
        from ..physics.rotational_coupling import RotationalCoupling
        for g in self.groups:
            if g.rotations.size:
                g.rotational = RotationalCoupling(g.operators, g.physics, self.solid_mesh, g.rotations.start,
                                                  self.n_displacement_dofs, triad=rot["triad"],
                                                  penalty=rot["penalty"], lm=rot["lm"],
                                                  enforcement=rot["enforcement"], constraint=rot["constraint"],
                                                  forces=rot["forces"])
                self.counts[f"coupling.rotational_{rot['enforcement']}"] += 1

    def _check_operators(self, operators):
        """Validate precomputed operators against the groups' meshes and the scene's LM type."""
        if not self.scene.coupled:
            raise ValueError("prepare(operators=...): the scene has no coupling (it needs a solid and beams)")
        operators = list(operators)
        if len(operators) != len(self.groups):
            raise ValueError(f"prepare(operators=...): expected {len(self.groups)} operator set(s), one per beam "
                             f"group ({', '.join(g.model for g in self.groups)}), got {len(operators)}")
        from ..elements.multiplier import multiplier
        from ..mortar.assemble import lm_numbering
        lm = self.scene.coupling["lm"]
        for k, (g, ops) in enumerate(zip(self.groups, operators)):
            if not all(hasattr(ops, a) for a in ("D", "M", "kappa", "lm", "n_lm")):
                raise TypeError(f"prepare(operators=...): operators[{k}] must be MortarOperators, "
                                f"got {type(ops).__name__}")
            if ops.lm != lm:
                raise ValueError(f"prepare(operators=...): operators[{k}] use lm={ops.lm!r}, the scene "
                                 f"coupling.lm={lm!r}")
            n_lm = lm_numbering(g.mesh, multiplier(lm))[1]
            want_D = (3 * n_lm, g.mesh.n_centreline_dofs)
            want_M = (3 * n_lm, 3 * self.n_solid_nodes)
            if ops.D.shape != want_D or ops.M.shape != want_M or np.shape(ops.kappa) != (n_lm,):
                raise ValueError(f"prepare(operators=...): operators[{k}] do not fit beam group {k} and the solid: "
                                 f"D {ops.D.shape} (expected {want_D}), M {ops.M.shape} (expected {want_M}), "
                                 f"kappa {np.shape(ops.kappa)} (expected ({n_lm},))")
        return operators

    def _fibre_field(self, families):
        """FibreField of ``solid.material.fibres``: a family without ``inside`` reinforces every
        element, one with ``inside`` the elements of its region (:meth:`~.sets.NamedSets.fibre_regions`)."""
        from ..physics.fibre_material import FibreField, fibre_family
        rows = []
        for i, (f, elements) in enumerate(zip(families, self.fibre_regions)):
            row = fibre_family(f["direction"], f["E"], f["volume_fraction"], f"solid.material.fibres[{i}]")
            rows.append((row, elements))
        return FibreField(self.solid_mesh.n_elements, rows)

    def _load_sets(self):
        """Per ``load`` entry: its resolved set (None for a body force) and, for surface loads,
        its boundary faces."""
        from ..physics.surface import boundary_faces
        out = []
        for i, item in enumerate(self.scene.loads):
            if item["type"] == "body":
                out.append((None, None))
                continue
            path = f"load[{i}].on"
            sel = self.select(item["on"], path)
            faces = None
            if item["type"] in ("traction", "pressure"):
                faces = boundary_faces(self.solid_mesh, sel[1])
                if len(faces) == 0:
                    raise SceneError(f"{path}: {item['on']!r} contains no boundary face of the solid")
            out.append((sel, faces))
        return out

    def _prepare_loads(self):
        from ..physics.surface import Pressure, traction_force
        n = self.n_displacement_dofs
        self.dead_load = np.zeros(n)
        self.pressures, self.moments = [], []
        for item, (sel, faces) in zip(self.scene.loads, self.load_sets):
            kind = item["type"]
            if kind == "body":
                self.dead_load[: 3 * self.n_solid_nodes] += self.solid_physics.body_force(item["value"])
                self.counts["load.body"] += 1
                continue
            if kind == "point":
                self.dead_load[self._set_dofs(sel, [0, 1, 2])] += np.tile(item["value"], len(self._set_dofs(sel, [0, 1, 2])) // 3)
                self.counts["load.point"] += 1
            elif kind in ("traction", "pressure"):
                if kind == "traction":
                    self.dead_load[: 3 * self.n_solid_nodes] += traction_force(self.solid_mesh, faces, item["value"])
                    self.counts["load.traction"] += 1
                else:
                    self.pressures.append(Pressure(self.solid_mesh, faces, item["value"]))
            elif kind == "line":
                # force per reference length along a whole beam: consistent nodal forces ∫ H_k q ds
                from ..physics.beam import line_force
                g, entry = sel[1], int(item["on"].split(":")[1])
                a, b = g.entry_elements[g.entries.index(entry)]
                dofs, f = line_force(g.mesh, np.arange(a, b), item["value"])
                np.add.at(self.dead_load, g.dofs.start + dofs, f)
                self.counts["load.line"] += 1
            elif kind == "line_moment":
                # moment per reference length: nodal moments ∫ L_k m ds on the rotation nodes (dead)
                from ..physics.simo_reissner import line_moment
                g, entry = sel[1], int(item["on"].split(":")[1])
                a, b = g.entry_elements[g.entries.index(entry)]
                nodes, moments = line_moment(g.physics, np.arange(a, b), item["value"])
                np.add.at(self.dead_load, (g.rotations.start + 3 * nodes[:, None] + np.arange(3)).ravel(),
                          moments.ravel())
                self.counts["load.line_moment"] += 1
            elif sel[1].rotations.size:
                # moment on the rotation nodes of a beam with a material frame: virtual work M·δθ
                # with spatial spins δθ, a dead load on the rotation unknowns
                r_idx = self._rotation_dofs(sel)
                self.dead_load[r_idx] += np.tile(item["value"], len(r_idx) // 3)
                self.counts["load.moment"] += 1
            else:   # moment on a Hermite beam end: acts on the node's tangent DOFs
                g, nodes = sel[1], sel[2]
                dofs = g.dofs.dofs(nodes[:1], [3, 4, 5])
                self.moments.append((dofs, item["value"]))
        if self.linear:
            # linear kinematics: pressure and moments are evaluated once, on the reference configuration
            for p in self.pressures:
                f, _ = p.evaluate(np.zeros(3 * self.n_solid_nodes), tangent=False)
                self.dead_load[: 3 * self.n_solid_nodes] += f
                self.counts["load.pressure"] += 1
            for dofs, moment in self.moments:
                from ..physics.beam import end_moment
                f, _ = end_moment(self._reference[dofs] if hasattr(self, "_reference") else self.reference()[dofs], moment)
                self.dead_load[dofs] += f
                self.counts["load.moment"] += 1
            self.pressures, self.moments = [], []

    def reference(self):
        """Reference values of the displacement unknowns' base configuration (positions/tangents)."""
        if not hasattr(self, "_reference"):
            ref = np.zeros(self.n_displacement_dofs)
            if self.solid_mesh is not None:
                ref[: 3 * self.n_solid_nodes] = self.solid_mesh.points.ravel()
            for g in self.groups:
                ref[g.dofs.slice] = g.mesh.centreline_dofs()
            self._reference = ref
        return self._reference

    # -- supports -------------------------------------------------------------------------------
    def _tangent_triplets(self):
        """(n_displacement_dofs // 3,) bool: which DOF triplets are Hermite tangents."""
        is_tangent = np.zeros(self.n_displacement_dofs // 3, dtype=bool)
        for g in self.groups:
            if g.type.element.has_tangents:
                first = g.dof_offset // 3
                is_tangent[first + 1: first + 2 * g.mesh.n_nodes: 2] = True
        return is_tangent

    def _rotation_triplets(self):
        """(n_displacement_dofs // 3,) bool: which DOF triplets are rotations (spins of rotation nodes)."""
        is_rotation = np.zeros(self.n_displacement_dofs // 3, dtype=bool)
        for g in self.groups:
            if g.rotations is not None and g.rotations.size:
                is_rotation[g.rotations.start // 3: g.rotations.stop // 3] = True
        return is_rotation

    def _position_triplets(self):
        """(n_displacement_dofs // 3,) bool: which DOF triplets move a point (solid nodes, beam positions)."""
        return ~(self._tangent_triplets() | self._rotation_triplets())

    def _mode_frame(self, dofs, is_tangent):
        """Centre and length scale of :meth:`rigid_body_modes`: the centroid and the largest extent
        of the positions among ``dofs`` (all when None); ``is_tangent`` marks the triplets that
        are no positions."""
        X = self.reference().reshape(-1, 3)
        triplets = np.arange(len(X)) if dofs is None else np.unique(dofs // 3)
        pos = triplets[~is_tangent[triplets]]
        centre = X[pos].mean(axis=0) if len(pos) else np.zeros(3)
        size = float(np.ptp(X[pos], axis=0).max()) if len(pos) > 1 else 1.0
        return centre, (size if size > 0 else 1.0)

    def rigid_body_modes(self, dofs=None):
        """(n_dofs, 6) rigid-body modes of the displacement DOFs (translations, rotations about the
        centroid of ``dofs``); tangent DOFs of Hermite beams rotate, never translate. In the basis of
        the unknowns (clamped tangents in their rotated frames), like ``fixed`` and ``free``."""
        from ..solvers.rigid import rigid_body_modes
        is_tangent = self._tangent_triplets()
        is_rotation = self._rotation_triplets()
        centre, size = self._mode_frame(dofs, is_tangent | is_rotation)
        R = rigid_body_modes(self.reference().reshape(-1, 3), is_tangent, centre=centre, scale=size,
                             rotation_mask=is_rotation if is_rotation.any() else None)
        return self.basis.to_unknowns(R)

    def check_supports(self):
        """Raise SceneError if a body can move as a rigid body or a beam has a zero-energy mode
        (:func:`~.checks.check_supports`; before any solve)."""
        checks.check_supports(self)

    def check_zero_energy_modes(self):
        """Raise SceneError if a beam has a zero-energy mode (:func:`~.checks.check_zero_energy_modes`)."""
        checks.check_zero_energy_modes(self)

    def check_linear_displacements(self, z):
        """Warn if the linear solution ``z`` moves a body by more than
        ``LINEAR_DISPLACEMENT_LIMIT`` of its size (:func:`~.checks.check_linear_displacements`)."""
        checks.check_linear_displacements(self, z, stacklevel=4)

    # -- the nonlinear system (see solvers.newton) ---------------------------------------------
    def prescribed(self, t):
        return t * self.fixed_values

    def _embed(self, K, offset):
        """Place a square block at (offset, offset) of an (n_displacement_dofs)² matrix."""
        n = self.n_displacement_dofs
        K = K.tocoo()
        return sp.csr_matrix((K.data, (K.row + offset, K.col + offset)), shape=(n, n))

    def _count(self, part, tangent):
        if self.linear:
            self.counts[f"{part}.stiffness"] += 1
        else:
            self.counts[f"{part}.internal_force"] += 1
            if tangent:
                self.counts[f"{part}.tangent"] += 1

    def internal(self, d, tangent=True, subtract=(), border=None):
        """Internal forces and tangent of solid + beams + penalty coupling at displacements ``d``.

        The tangent also gets the terms ``subtract`` (``(L, index, s)``: ``− s L`` placed at
        ``index``, the loads' tangents, in order) and, with ``border`` (the constraint matrix B of
        Lagrange multipliers), becomes the saddle-point matrix ``[[K, Bᵀ], [B, 0]]``. All of it is
        summed on one cached pattern (:mod:`.tangent`), unless rotational penalty coupling adds its
        state-dependent pattern: then those terms follow as scipy sums, in the same order.
        """
        n = self.n_displacement_dofs
        r = np.zeros(n)
        blocks = []          # (tangent, offset or index array of its unknowns)
        penalty = self.scene.coupled and not self.lagrange
        framed = any(g.rotations.size for g in self.groups)   # beams with rotations: unknowns not contiguous
        rotational = [g for g in self.groups if g.rotational is not None and g.rotational.enforcement == "penalty"]
        late = bool(rotational)                 # loads' and border terms after the rotational penalty's
        on_pattern = tangent and (penalty or framed or (not late and (bool(subtract) or border is not None)))
        if self.solid_mesh is not None:
            nS = 3 * self.n_solid_nodes
            self._count("solid", tangent)
            if on_pattern and not self.linear:
                # the solid's element kernel adds straight into the tangent's data (model.tangent)
                def fill(data, positions):
                    r[:nS] += self.solid_physics.add_tangent_into(d[:nS], data, positions)
                blocks.append((FilledBlock(*self.solid_physics.pattern, fill), 0))
            else:
                f, K = self.solid_physics.evaluate(d[:nS], tangent=tangent)
                r[:nS] = f
                blocks.append((K, 0))
        for g in self.groups:
            sl = g.dofs.slice
            if g.rotations.size:
                f, K = g.physics.evaluate(d[sl], d[g.rotations.slice].reshape(-1, 3), tangent=tangent)
                self._count("beam", tangent)
                idx = np.concatenate([np.arange(g.dofs.start, g.dofs.stop), np.arange(g.rotations.start,
                                                                                      g.rotations.stop)])
                r[idx] = f
                blocks.append((K, idx))
                continue
            f, K = g.physics.evaluate(d[sl], tangent=tangent)
            self._count("beam", tangent)
            r[sl] = f
            blocks.append((K, g.dofs.start))
        if penalty:
            r += self.coupling_stiffness @ d
        K = None
        if on_pattern:
            # a sum of blocks on one cached pattern (see model.tangent); the zeros removed are those
            # scipy's sums would remove: all of them once anything is summed, none of the border's
            # (as sp.bmat keeps them), none at all for solid + beams + border alone (block_diag and
            # bmat keep them)
            summed = penalty or framed or (not late and bool(subtract))
            size = n if late or border is None else n + border.shape[0]
            constant = self.coupling_stiffness if penalty else None
            zeros = "eliminate" if summed else "keep"
            if not late and border is not None:
                constant = self._border_matrix(border)
                zeros = "keep_constant" if summed else "keep"
            if self._tangent_pattern is None or self._tangent_pattern.n != size:
                self._tangent_pattern = TangentPattern(size)
            K = self._tangent_pattern.assemble(blocks, constant, () if late else subtract, zeros=zeros)
        elif tangent:
            K = sp.block_diag([Kb for Kb, _ in blocks], format="csr")
        for g in rotational:
            f, Kr = g.rotational.evaluate(d[:3 * self.n_solid_nodes], d[g.rotations.slice].reshape(-1, 3),
                                          tangent=tangent)
            self.counts["coupling.rotational_penalty"] += 1
            r += f
            if tangent:
                K = K + Kr
        if tangent and (late or not on_pattern):
            for L, index, scale in subtract:
                K = K - scale * self._placed(L, index)
            if border is not None:
                K = sp.bmat([[K, border.T], [border, None]], format="csr")
        return r, K

    def _placed(self, L, index):
        """Square block ``L`` placed at ``index`` (an offset or the unknowns of its rows and columns)
        in an (n_displacement_dofs)² matrix."""
        if isinstance(index, (int, np.integer)):
            return self._embed(L, index)
        L = L.tocoo()
        index = np.asarray(index)
        return sp.csr_matrix((L.data, (index[L.row], index[L.col])), shape=(self.n_displacement_dofs,) * 2)

    def _border_matrix(self, B):
        """``[[0, Bᵀ], [B, 0]]`` of the constraint matrix ``B``, built once (B does not change)."""
        if self._border is None or self._border[0] is not B:
            self._border = (B, sp.bmat([[sp.csr_matrix((self.n_displacement_dofs,) * 2), B.T], [B, None]],
                                       format="csr"))
        return self._border[1]

    def update(self, z, free, dz):
        """Apply a Newton increment ``dz`` (on the ``free`` unknowns) to ``z`` in place.

        Additive for every unknown but rotations: a rotation node's increment is a spatial spin
        Δθ, and its total rotation vector becomes ψ ← log(exp(Δθ) exp(ψ)) (the multiplicative
        update the residual's linearisation in spins asks for). Without rotations this is
        ``z[free] += dz``.
        """
        framed = [g for g in self.groups if g.rotations.size]
        if not framed:
            z[free] += dz
            return
        step = np.zeros(len(z))
        step[free] = dz
        self.counts["beam.rotation_update"] += 1
        for g in framed:
            b = g.rotations
            spin = step[b.slice].reshape(-1, 3).copy()
            step[b.slice] = 0.0
            if self.twist_starts.size:
                # twist-held nodes: total rotation vectors in their frames, updated additively
                held = (self.twist_starts[(self.twist_starts >= b.start) & (self.twist_starts < b.stop)] - b.start) // 3
                step[b.start + 3 * held[:, None] + np.arange(3)] = spin[held]
                spin[held] = 0.0
            psi = z[b.slice].reshape(-1, 3)
            moved = np.any(spin != 0.0, axis=1)          # the others keep their bits
            psi[moved] = g.physics.update(psi, spin)[moved]
            z[b.slice] = psi.ravel()
        z[free] += step[free]

    def residual(self, z, t, tangent=True):
        """Residual ``r = f_int + (coupling) − t f_ext`` over all unknowns, and its Jacobian.

        ``z``, ``r`` and the Jacobian are in the basis of the unknowns (``self.basis``: clamped
        tangents in their rotated frames); the physics is evaluated on physical components.
        """
        n = self.n_displacement_dofs
        d = self.basis.to_physical(z[:n])
        nS = 3 * self.n_solid_nodes
        # the loads' forces and tangents first: the tangents are summed with the internal ones
        # (model.tangent), the forces applied after the internal forces as before
        loads, subtract = [], []
        for p in self.pressures:
            f, Kp = p.evaluate(d[:nS], tangent=tangent)
            self.counts["load.pressure"] += 1
            loads.append((slice(0, nS), t * f))
            if tangent:
                self.counts["load.pressure_tangent"] += 1
                subtract.append((Kp, 0, t))
        if self.moments:
            from ..physics.beam import end_moment
            q = self.reference() + d
            for dofs, moment in self.moments:
                f, Km = end_moment(q[dofs], t * moment)
                self.counts["load.moment"] += 1
                loads.append((dofs, f))
                if tangent:
                    # every entry stored, zeros too: the pattern must not depend on the state
                    m = len(dofs)
                    subtract.append((sp.csr_matrix((np.asarray(Km, dtype=float).ravel(), np.tile(np.arange(m), m),
                                                    np.arange(0, m * m + 1, m)), shape=(m, m)), np.asarray(dofs), 1.0))
        border = self.lagrange and not self.rotational_lagrange
        B = self.constraint_matrix if border else None
        r, K = self.internal(d, tangent, subtract, B if tangent else None)
        r -= t * self.dead_load
        for where, f in loads:
            r[where] -= f
        if border:
            lam = z[n:]
            r = np.concatenate([r + B.T @ lam, B @ d])
        elif self.n_multipliers:
            r, K = self._saddle_residual(z, d, r, K, tangent)
        if self.twist_starts.size:
            r, K = self._twist_jacobian(d, r, K)
        r, K = self.basis.to_unknowns(r), self.basis.matrix(K)
        self.last_residual = r
        return r, (K.tocsr() if tangent else None)

    @property
    def rotational_lagrange(self):
        """True when ``coupling.rotational.enforcement = "lagrange"``: rotational multipliers follow
        the positional ones among the unknowns."""
        rot = self.scene.coupling.get("rotational") if self.scene.coupled else None
        return rot is not None and rot["enforcement"] == "lagrange"

    def _saddle_residual(self, z, d, r, K, tangent):
        """Residual and tangent with the constraint rows of all multipliers: the positional ones
        (``B d``, if ``coupling.enforcement = "lagrange"``), then each group's rotational ones
        (the nonlinear ``g(u_S, θ_B)``, linearised to ``G``; the multipliers add ``λᵀ ∂²g`` to the
        stiffness block)."""
        n, nS = self.n_displacement_dofs, 3 * self.n_solid_nodes
        lam, rows, blocks, start = z[n:], [], [], 0
        r = r.copy()
        if self.lagrange:
            B = self.constraint_matrix
            start = B.shape[0]
            r += B.T @ lam[:start]
            rows.append(B @ d)
            blocks.append(B)
        for g in self.groups:
            if g.rotational is None or g.rotational.enforcement != "lagrange":
                continue
            k = g.rotational.n_multipliers
            f, c, G, K_lam = g.rotational.constraint(d[:nS], d[g.rotations.slice].reshape(-1, 3),
                                                     lam[start: start + k], tangent=tangent)
            self.counts["coupling.rotational_lagrange"] += 1
            start += k
            r += f
            rows.append(c)
            if tangent:
                K = K + K_lam
                blocks.append(G)
        r = np.concatenate([r] + rows)
        if tangent:
            B = sp.vstack(blocks, format="csr")
            self.last_constraint_rows = B
            K = sp.bmat([[K, B.T], [B, None]], format="csr")
        return r, K

    def _auxiliary_space(self, lagrange=False):
        """True when the AMG path uses the auxiliary-space preconditioner: beams penalty-coupled
        to a solid (plain AMG on the penalty system needs hundreds of iterations at ε = 1e3 E),
        or with ``lagrange=True``, coupled by multipliers (the block solver's augmented stiffness
        is such a penalty system)."""
        return (self.solid_mesh is not None and bool(self.groups) and self.scene.coupled
                and self.lagrange == lagrange)

    def _follow_split(self):
        """``solid``, ``beam`` (positions among the free DOFs) and the prolongation ``P`` (free
        beam DOFs × free solid DOFs) of :func:`~mortar1d3d.physics.coupling.follow_operator`;
        built once, since the coupling operators are constant."""
        if self._follow is None:
            from ..physics.coupling import follow_operator
            nS = 3 * self.n_solid_nodes
            free = self.free[self.free < self.n_displacement_dofs]
            blocks = [follow_operator(g.operators, g.mesh) for g in self.groups]
            rotations = sum(g.rotations.size for g in self.groups)
            if rotations:       # rotations (after every centreline block) do not follow the solid's nodes
                blocks.append(sp.csr_matrix((rotations, 3 * self.n_solid_nodes)))
            P = sp.vstack(blocks, format="csr")           # groups are contiguous after the solid
            P = self.basis.to_unknowns(P, offset=nS)      # rows of clamped tangents: rotated frames
            solid = np.flatnonzero(free < nS)
            beam = np.flatnonzero(free >= nS)
            P = P[free[beam] - nS][:, free[solid]].tocsr()
            self._follow = dict(solid=solid, beam=beam, prolongation=P)
            self.counts["linear_solver.follow_operator"] += 1
        return self._follow

    def _dependent_multipliers(self, B, beam):
        """Dependent rows of the constraint block ``B`` (free columns), found once per model.

        Warns (CouplingWarning) naming the beams and LM nodes whose rows are left out; raises
        SceneError if prescribed values contradict them (the constraints then have no solution).
        """
        if getattr(self, "_dependent", None) is None:
            from ..elements.multiplier import multiplier
            from ..mortar.assemble import lm_numbering
            from ..solvers.linear import DEPENDENT_ROW_TOLERANCE, dependent_rows
            dep = dependent_rows(B, beam)
            if len(dep):
                # each row of B: (beam entry, LM node as a row of Result.line_load or, rotational, of
                # Result.line_moment, component, rotational?)
                entry, lm_node, comp, rotational, first = [], [], [], [], [0, 0]
                for g in self.groups:
                    for kind, part in ((0, g.coupling if self.lagrange else None),
                                       (1, g.rotational if self.rotational_lagrange else None)):
                        if part is None:
                            continue
                        if kind:
                            index, n_lm = part.lm_index, part.n_lm
                        else:
                            index, n_lm = lm_numbering(g.mesh, multiplier(self.scene.coupling["lm"]))
                        owner = np.zeros(n_lm, dtype=np.int64)
                        for k, (start, stop) in enumerate(g.entry_elements):
                            owner[index[start:stop][index[start:stop] >= 0]] = g.entries[k]
                        rows = part.coupled_rows
                        entry.append(owner[rows // 3])
                        lm_node.append(first[kind] + rows // 3)
                        comp.append(rows % 3)
                        rotational.append(np.full(len(rows), kind, dtype=bool))
                        first[kind] += n_lm
                # the rotational rows follow all positional rows (the order of the multipliers)
                order = np.argsort(np.concatenate(rotational), kind="stable")
                is_rotational = np.concatenate(rotational)[order]
                entry, lm_node, comp, rot = (np.concatenate(v)[order][dep.rows]
                                             for v in (entry, lm_node, comp, rotational))
                parts = []
                for e in np.unique(entry):
                    for kind in np.unique(rot[entry == e]):
                        at = (entry == e) & (rot == kind)
                        nodes = [f"{j} ({', '.join('xyz'[c] for c in comp[at & (lm_node == j)])})"
                                 for j in np.unique(lm_node[at])]
                        parts.append(f"beams[{e}] {'rotational ' if kind else ''}LM nodes {', '.join(nodes)}")
                what = "; ".join(parts)
                C = dep.combinations
                # prescribed values must satisfy the dropped rows through the kept ones
                # (fixed DOFs and values are in the unknowns' basis: clamped tangents in rotated frames);
                # checked on the linear positional rows only: the rotational constraint is nonlinear
                positional = np.asarray(abs(C) @ is_rotational.astype(float)).ravel() == 0
                if self.lagrange and positional.any():
                    Bu = self.constraint_matrix @ self.basis.matrix_T(self.n_displacement_dofs) if self.basis \
                        else self.constraint_matrix
                    Cp = C[positional][:, :Bu.shape[0]]
                    Bf, v = Bu.tocsc()[:, self.fixed_dofs], self.fixed_values
                    gap = np.abs(Cp @ (Bf @ v))
                    size = abs(Cp) @ (abs(Bf) @ np.abs(v))
                    # entries of B that vanish in exact arithmetic (the integral of a shape function against a
                    # multiplier shape it is orthogonal to) come out as round-off of their row's size: where
                    # a combination sees only such entries on the prescribed DOFs, gap and size are both
                    # round-off, so the row sizes' round-off at the largest prescribed value counts too
                    row_size = np.asarray(abs(Bu).sum(axis=1)).ravel()
                    roundoff = 64 * np.finfo(float).eps * (abs(Cp) @ row_size) * np.abs(v).max(initial=0.0)
                    if np.any(gap > DEPENDENT_ROW_TOLERANCE * size + roundoff):
                        raise SceneError(f"dirichlet: the prescribed values contradict the coupling: the rows of "
                                         f"{what} are combinations of other coupling rows, and the prescribed "
                                         "displacements satisfy those but not these (prescribe values the embedded "
                                         "beams can follow)")
                key, lm = "coupling.lm", self.scene.coupling["lm"]
                if rot.any():
                    key, lm = "coupling.rotational.lm", self.scene.coupling["rotational"]["lm"]
                warnings.warn(f"{key}: the coupling rows of {what} are combinations of the other rows (the "
                              f"multipliers, lm = {lm!r}, are richer than what the solid mesh, or the "
                              "integration points along the beam (n_gauss), resolve, or supports fixed what they act "
                              "on); they are left out, and λ there is the least-norm line load transferring the same "
                              "forces. A lower lm (line2), more integration points or a finer solid mesh avoids this",
                              CouplingWarning, stacklevel=4)
            self._dependent = dep
        return self._dependent

    def _solve_reusing(self, solve, method):
        """``solve(None)``; in a nonlinear analysis with an iterative method, with the preconditioner
        of an earlier solve while that serves."""
        if self.linear or method == "direct" or not self.reuse_preconditioner:
            return solve(None)
        if self._preconditioner is None:
            from ..solvers.reuse import ReusedPreconditioner
            self._preconditioner = ReusedPreconditioner()
        return self._preconditioner.solve(solve)

    def solve_linear(self, A, b, x0=None, rtol=None):
        """Solve a reduced (Dirichlet DOFs removed) linear system of this model.

        ``rtol``: relative residual to reach (iterative solvers; default ``analysis.rtol``, what
        a linear analysis needs of its one solve). The solver's info dict is kept in
        ``last_linear_info`` (its ``note``, if any, says that a solver broke down and which one
        took over).
        """
        from ..solvers.linear import solve_linear, solve_saddle
        rtol = self.scene.analysis["rtol"] if rtol is None else rtol
        method = self.linear_solver_method(len(b))
        self.counts[f"linear_solver.{method}"] += 1
        free = self.free
        # AMG aggregates 3×3 blocks only when every node keeps all or none of its components
        triplets = np.bincount(free // 3, minlength=self.n_unknowns // 3 + 1)
        block = 3 if np.isin(triplets, (0, 3)).all() else 1
        if not self.n_multipliers:
            options = dict(method=method, rtol=rtol)
            if method == "amg":
                options.update(near_nullspace=self.rigid_body_modes()[free], block_size=block)
                if self._auxiliary_space():
                    options.update(method="aux", **self._follow_split())
            x, info = self._solve_reusing(lambda kept: solve_linear(A, b, preconditioner=kept, **options), method)
            self.last_linear_info = info
            return x
        n = self.n_displacement_dofs
        primal = free < n
        p_idx = np.flatnonzero(primal)
        m_idx = np.flatnonzero(~primal)
        K = A[p_idx][:, p_idx]
        B = A[m_idx][:, p_idx]
        kappa = np.concatenate([np.repeat(g.operators.kappa[g.coupling.coupled], 3) for g in self.groups
                                if self.lagrange]
                               + [g.rotational.kappa[g.rotational.coupled_rows // 3] for g in self.groups
                                  if g.rotational is not None and g.rotational.enforcement == "lagrange"])
        solid = np.flatnonzero(free[p_idx] < 3 * self.n_solid_nodes)
        beam = np.flatnonzero(free[p_idx] >= 3 * self.n_solid_nodes)
        R = self.rigid_body_modes()[free[p_idx]]
        options = dict(method="direct" if method == "direct" else "block", solid=solid, beam=beam, near_nullspace=R,
                       rtol=rtol, block_size=block, dependent=self._dependent_multipliers(B, beam))
        if method != "direct" and self._auxiliary_space(lagrange=True) and len(solid) and len(beam):
            options["prolongation"] = self._follow_split()["prolongation"]
        # γ (augmentation and scaling of the constraint rows) from the operators, never the penalty
        x, lam, info = self._solve_reusing(
            lambda kept: solve_saddle(K, B, kappa, b[p_idx], b[m_idx], preconditioner=kept, **options), method)
        self.last_linear_info = info
        out = np.empty(len(b))
        out[p_idx], out[m_idx] = x, lam
        return out

