"""Results of :func:`mortar1d3d.solve`: fields, line loads, reactions, history, VTU/PVD output."""
import shutil
import uuid
from pathlib import Path

import numpy as np

from .elements.multiplier import multiplier as multiplier_type
from .elements.multiplier import shape as lm_shape
from .mortar.assemble import lm_numbering


def beam_output_fields(beam_type, sample, s):
    """The output fields of a beam type from ``physics.sample`` at ``s`` points per element: each
    (n_elements, s, ...) array flattened to one row per point, a triad also as its three base vectors
    ``g1``, ``g2``, ``g3`` (vector fields). Serial and parallel output use it alike."""
    if "triads" in sample:
        sample = dict(sample)
        for k in range(3):
            sample[f"g{k + 1}"] = sample["triads"][..., :, k]
    out = {}
    for key in beam_type.output_fields:
        if key in sample:
            v = np.asarray(sample[key])
            out[key] = v.reshape(v.shape[0] * s, *v.shape[2:])
    return out


class Result:
    """What a solve produced.

    Attributes
    ----------
    z : (n_unknowns,) float64
        All unknowns at the end (Model layout; physical components, clamped tangents included).
    solid_displacement : (n_solid_nodes, 3) float64
    beam_displacement : (n_beam_nodes, 3) float64
        Centreline position displacements, beams in scene order, each beam's nodes in order.
    beam_tangent_displacement : (n_beam_nodes, 3) float64
        Change of the nodal tangent vectors (zero rows for truss beams).
    beam_rotation : (n_beam_nodes, 3) float64
        Total rotation vector ψ of the triad at each beam node, ``Λ = exp(ψ) Λ0`` (zero rows for
        beams without rotations).
    line_load : (n_lm, 3) float64
        Coupling line load λ at the LM nodes (beam groups in order of first appearance;
        zero at LM nodes no integration point touched).
    line_moment : (n_rotational_lm, 3) float64
        Rotational coupling (``coupling.rotational``) line moments at the rotational LM nodes,
        spatial components, moment per length (N·m/m): ``ε κ⁻¹ g`` with penalty (``g``
        linearised at the reference state in a linear analysis), the multipliers with Lagrange
        enforcement. Beam groups with rotational coupling in order; LM nodes in the order of the
        rotational multiplier functions (``coupling.rotational.lm``) along each group's elements;
        zero at LM nodes no integration point touched. Empty (0 rows) without rotational
        coupling. ``line_moments(k)`` gives them after load step k.
    steps : list of StepRecord
        Per converged load step: load factor, Newton residual norms, iterations, cuts.
    reactions : list of (3,) float64
        Sum of the support forces over each ``[[dirichlet]]`` entry's position DOFs.
    counts : collections.Counter
        The effects that ran and how often (names as in :func:`mortar1d3d.plan`).
    coupled_length, beam_length : (n_beams,) float64
        Per scene beam: the reference length the coupling integrates over (the part inside the
        solid) and the whole reference length; ``coupled_length`` is all zeros without a
        coupling. A beam with ``coupled_length < beam_length`` got a CouplingWarning.
    wall_time : float
    """

    def __init__(self, model, z, steps, history, wall_time=0.0):
        # the solvers work in the model's basis of unknowns (clamped tangents in rotated frames);
        # a result holds physical components
        z, history = model.basis.to_physical(z), [model.basis.to_physical(h) for h in history]
        self.model, self.z, self.steps, self.history, self.wall_time = model, z, steps, history, wall_time
        self.scene = model.scene
        self.counts = model.counts
        self.solid_displacement = z[: 3 * model.n_solid_nodes].reshape(-1, 3).copy()
        pos, tan, rot, lengths = [], [], [], []
        for entry in range(len(self.scene.beams)):
            g = model.entry_group[entry]
            a, b = g.entry_elements[g.entries.index(entry)]
            lengths.append(g.mesh.lengths[a:b].sum())
            nodes = self._entry_nodes(g, entry)
            q = z[g.dofs.slice].reshape(g.mesh.n_nodes, -1)
            pos.append(q[nodes, :3])
            tan.append(q[nodes, 3:6] if g.type.element.has_tangents else np.zeros((len(nodes), 3)))
            # a mesh node is the rotation node of the same index
            rot.append(z[g.rotations.slice].reshape(-1, 3)[nodes] if g.rotations.size else np.zeros((len(nodes), 3)))
        self.beam_displacement = np.vstack(pos) if pos else np.zeros((0, 3))
        self.beam_tangent_displacement = np.vstack(tan) if tan else np.zeros((0, 3))
        self.beam_rotation = np.vstack(rot) if rot else np.zeros((0, 3))
        self.line_load = self._line_load(z)
        self.line_moment = self._line_moment(z)
        n_beams = len(self.scene.beams)
        coupled = getattr(model, "coupled_length", None)
        self.coupled_length = np.array(coupled, dtype=float) if coupled is not None else np.zeros(n_beams)
        self.beam_length = np.array(lengths, dtype=float)
        r = getattr(model, "last_residual", None)
        r = model.basis.to_physical(r) if r is not None else None
        self.reactions = []
        for dofs in model.dirichlet_dofs:
            force = np.zeros(3)
            if r is not None:
                np.add.at(force, dofs % 3, r[dofs])
            self.reactions.append(force)

    # -- helpers --------------------------------------------------------------------------------
    @staticmethod
    def _entry_nodes(g, entry):
        k = g.entries.index(entry)
        a, b = g.entry_elements[k]
        return np.unique(g.mesh.elements[a:b])

    def _line_load(self, z):
        model = self.model
        n = model.n_displacement_dofs
        parts, start = [], n
        for g in model.groups:
            if g.coupling is None:
                continue
            lam = None
            if model.lagrange:
                k = g.coupling.n_multipliers
                lam = z[start: start + k]
                start += k
            parts.append(g.coupling.line_load(z[:n], lam))
        return np.vstack(parts) if parts else np.zeros((0, 3))

    def _line_moment(self, z):
        model = self.model
        n, nS = model.n_displacement_dofs, 3 * model.n_solid_nodes
        # rotational multipliers follow the positional ones
        start = n + sum(g.coupling.n_multipliers for g in model.groups if g.coupling is not None)
        parts = []
        for g in model.groups:
            rc = g.rotational
            if rc is None:
                continue
            k = rc.n_multipliers
            parts.append(rc.line_moment(z[:nS], z[g.rotations.slice].reshape(-1, 3), z[start: start + k],
                                        linear=model.linear))
            start += k
        return np.vstack(parts) if parts else np.zeros((0, 3))

    def line_moments(self, step=-1):
        """Rotational line moments (as :attr:`line_moment`) after load step ``step`` (an index of
        :attr:`steps`; default the last)."""
        return self._line_moment(self.history[step])

    def coupling_summary(self, max_lines=10):
        """Lines of text: the coupled length of every beam (at most ``max_lines`` beams listed,
        partly coupled ones first), then the total. Empty without a coupling."""
        if not (self.scene.coupled and len(self.beam_length)):
            return []
        fraction = self.coupled_length / np.where(self.beam_length > 0, self.beam_length, 1.0)
        order = np.argsort(fraction, kind="stable")
        lines = [f"beams[{i}]: coupled length {self.coupled_length[i]:.6g} of {self.beam_length[i]:.6g} "
                 f"({fraction[i]:.1%})" for i in order[:max_lines]]
        if len(order) > max_lines:
            lines.append(f"... {len(order) - max_lines} more beams")
        total, coupled = self.beam_length.sum(), self.coupled_length.sum()
        limit = self.model.UNCOUPLED_FRACTION_LIMIT
        partly = int(np.count_nonzero(self.coupled_length < (1.0 - limit) * self.beam_length))
        lines.append(f"all {len(order)} beams: coupled length {coupled:.6g} of {total:.6g} "
                     f"({coupled / total:.1%}); {partly} partly or not coupled")
        return lines

    @property
    def load_factor(self):
        return self.steps[-1].load_factor if self.steps else 0.0

    def __repr__(self):
        umax = np.abs(self.solid_displacement).max() if self.solid_displacement.size else 0.0
        bmax = np.abs(self.beam_displacement).max() if self.beam_displacement.size else 0.0
        return (f"Result({len(self.steps)} steps, {sum(s.iterations for s in self.steps)} iterations, "
                f"max |u_S| {umax:.4g}, max |u_B| {bmax:.4g}, {self.wall_time:.2f} s)")

    # -- output ---------------------------------------------------------------------------------
    def write(self, directory, samples_per_element=8, *, compression="zlib"):
        """Write a ParaView series: ``result.pvd`` plus VTU files per load step.

        Per step k (k = 0 is the reference state): ``solid_<k>.vtu`` (point data
        ``displacement``; cell data ``green_lagrange_strain`` and ``cauchy_stress`` as 3×3
        tensors, averaged over each element's Gauss points), ``beams_<k>.vtu`` (the reference
        centrelines sampled as polylines with ``displacement``, ``axial_force``, ``curvature`` and
        the coupling ``line_load`` λ(η), the scene ``beam`` index, the ``fibre`` and the
        ``arc_length`` along it; beams with rotations also the triad ``g1``, ``g2``, ``g3``, the
        spatial force and moment resultants ``n``, ``m`` and the elastic strains ``Gamma``
        (Γ − Γ0: axial and shear) and ``K`` (K − K0: torsion and bending) in the material frame,
        and with ``coupling.rotational`` its ``line_moment`` (:attr:`line_moment` interpolated
        with the rotational multiplier functions)),
        ``segments_<k>.vtu`` and ``points_<k>.vtu`` (the coupling's segments and integration points
        at their reference positions, with the beams' ``displacement``). Open ``result.pvd`` and
        apply *Warp By Vector* with ``displacement``: solid, beams, segments and points all move.

        Everything is written into a temporary directory first and moved into ``directory`` only
        when complete: a failure leaves no partial files.

        Returns
        -------
        list of pathlib.Path
        """
        from .io.vtu import (displacement_coefficients, write_beams, write_integration_points, write_pvd,
                             write_segments, write_solid)
        directory = Path(directory)
        directory.parent.mkdir(parents=True, exist_ok=True)
        tmp = directory.parent / f".{directory.name}.tmp-{uuid.uuid4().hex[:8]}"
        tmp.mkdir()
        model = self.model
        try:
            entries, written = [], []
            states = [(0.0, np.zeros_like(self.z))] + [(s.load_factor, z) for s, z in zip(self.steps, self.history)]
            for k, (t, z) in enumerate(states):
                files = []
                if model.solid_mesh is not None:
                    u = z[: 3 * model.n_solid_nodes]
                    fields = model.solid_physics.cell_fields(u)
                    cell = {name: np.asarray(v).reshape(len(v), -1) for name, v in fields.items()}
                    files.append(write_solid(tmp / f"solid_{k:04d}.vtu", model.solid_mesh,
                                             point_data={"displacement": u.reshape(-1, 3)}, cell_data=cell,
                                             compression=compression).name)
                lam_all = self._line_load(z)
                moments_all = self._line_moment(z)
                lm_start = moment_start = 0
                for gi, g in enumerate(model.groups):
                    suffix = f"{gi}_" if len(model.groups) > 1 else ""
                    d = z[g.dofs.slice]         # the group's centreline unknowns (rotations are a block of their own)
                    data = self._beam_samples(g, z, samples_per_element)
                    data["beam"] = np.repeat(g.entries, [b - a for a, b in g.entry_elements])
                    if g.coupling is not None:
                        data["line_load"] = self._lm_samples(g.mesh, g.operators.lm,
                                                             lam_all[lm_start: lm_start + g.coupling.n_lm],
                                                             samples_per_element)
                        lm_start += g.coupling.n_lm
                    if g.rotational is not None:
                        data["line_moment"] = self._lm_samples(
                            g.mesh, g.rotational.lm, moments_all[moment_start: moment_start + g.rotational.n_lm],
                            samples_per_element)
                        moment_start += g.rotational.n_lm
                    files.append(write_beams(tmp / f"beams_{suffix}{k:04d}.vtu", g.mesh, samples_per_element,
                                             point_data=data, compression=compression).name)
                    if g.operators is not None:
                        # segments and points at every step, with the beams' centreline displacement,
                        # so that Warp By Vector moves them
                        u = displacement_coefficients(g.mesh, d) if len(d) == g.mesh.n_centreline_dofs else None
                        files.append(write_segments(tmp / f"segments_{suffix}{k:04d}.vtu", g.mesh, g.operators,
                                                    displacement=u, compression=compression).name)
                        files.append(write_integration_points(tmp / f"points_{suffix}{k:04d}.vtu", g.operators,
                                                              beams=g.mesh, displacement=u,
                                                              compression=compression).name)
                for part, name in enumerate(files):
                    entries.append((t, part, name))
                written += files
            written.append(write_pvd(tmp / "result.pvd", entries).name)
            directory.mkdir(parents=True, exist_ok=True)
            for name in written:
                (tmp / name).replace(directory / name)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return [directory / name for name in written]

    @staticmethod
    def _beam_samples(g, z, s):
        eta = np.linspace(-1.0, 1.0, s)
        d = z[g.dofs.slice]
        if g.rotations.size:
            sample = g.physics.sample(d, z[g.rotations.slice].reshape(-1, 3), eta)
        else:
            sample = g.physics.sample(d, eta)
        return beam_output_fields(g.type, sample, s)

    @staticmethod
    def _lm_samples(mesh, lm_name, lam, s):
        """Values (n_lm, 3) at the LM nodes of multiplier functions ``lm_name``, interpolated at
        ``s`` points of every element: (n_elements s, 3)."""
        lm = multiplier_type(lm_name)
        index, _ = lm_numbering(mesh, lm)
        eta = np.linspace(-1.0, 1.0, s)
        Phi = np.zeros((s, 4))
        for i, e in enumerate(eta):
            lm_shape.py_func(lm.n_functions, e, Phi[i])
        Phi = Phi[:, : lm.n_functions]
        values = np.einsum("sj,ejc->esc", Phi, lam[index[:, : lm.n_functions]])
        return values.reshape(-1, 3)
