"""What accuracy costs in time: the integration trade-off study of issue 5.

Measures, on a set of scenes, every integration variant of :func:`assemble_mortar`
(element-based, segment-based and ``"auto"`` with a range of Gauss counts) for

- **cost**: median wall time of the whole ``assemble_mortar`` call (JIT excluded: one untimed
  call first), split into the stages of ``ops.timings``, and the peak of memory allocated
  through Python/NumPy during one call (``tracemalloc``; the kernels' few per-chunk scratch
  buffers are not seen by it);
- **accuracy**: errors of D and M against a converged reference (segment-based with a high
  Gauss count): relative Frobenius norm ``‖A - A_ref‖_F / ‖A_ref‖_F`` and worst entry
  ``max |A - A_ref| / max |A_ref|``. The reference itself is checked against an independent
  adaptive quadrature (:func:`pair_reference_check`: ``scipy.integrate.quad_vec`` over each
  segment, own centreline formulas, own Newton projection);
- **solution error**: the displacement at a monitor point after a linear solve with each
  variant's operators, against the solve with the reference operators
  (:class:`MonitorProblem`, :func:`solution_monitor`, :func:`monitor_error`): a clamped,
  self-weighted linear elastic cube with stiff fibres, penalty-coupled; the solid is factorised
  once per mesh (:class:`ClampedSolid`) and each variant costs one small dense solve. Straight
  fibres only (:data:`MONITOR_KINDS`): the fibres are torsion-free beams, whose theory needs
  initially straight centrelines.

Also: scaling of time and memory with the number of integration points (log-log fit), cold vs
warm start in fresh processes, and the ``"auto"`` target (segment-based accuracy at <= 1.3x the
element-based time) on the benchmark scene ``fibre_cube(20, 1000, 20)``.

Entry points: :func:`run_study` (returns a plain dict of numbers), :func:`write_report` (Markdown,
PNG plots, JSON), :func:`make_report` (both; used by ``mortar1d3d bench report``).
"""
import datetime
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from . import generate
from .mesh import BeamMesh
from .mortar.assemble import assemble_mortar, lm_numbering

#: scene kinds: (solid element, curved fibres, distortion amplitude of the solid mesh)
SCENE_KINDS = {
    "straight fibres, hex8": ("hexahedron", False, 0.0),
    "curved fibres, hex27": ("hexahedron27", True, 0.1),
    "curved fibres, tet10": ("tetra10", True, 0.1),
}
#: the scene kinds the solution monitor runs on. Its fibres are torsion-free beams, which hold for
#: initially straight centrelines only (issue 16). A truss is no substitute for the curved kinds: it
#: needs operators of a line centreline, not the Hermite ones this study measures, and half of the
#: scenes have fibres partly outside the cube, where a truss has no stiffness against sideways
#: motion. Curved fibres wait for a beam with a material frame (Simo–Reissner).
MONITOR_KINDS = tuple(k for k, (_, curved, _) in SCENE_KINDS.items() if not curved)
#: beam element length over solid element size
RATIOS = (0.25, 1.0, 4.0)
EMBEDDINGS = ("embedded", "partly outside")
STAGES = ("search", "segmentation", "integration_points", "assembly", "csr", "other")


def _stages(timings):
    """The stages of ``ops.timings``, plus ``other``: the rest of the total (certificates, point records)."""
    out = {k: timings.get(k, 0.0) for k in STAGES[:-1]}
    out["other"] = max(0.0, timings.get("total", 0.0) - sum(out.values()))
    return out
INTEGRATIONS = ("element", "segment", "auto")


@dataclass
class StudyConfig:
    """Sizes and variants of one study run (see :func:`preset`)."""

    name: str = "full"
    cells: int = 8                     # solid cells per cube edge (h_S = 1 / cells)
    fibres: int = 12
    fibre_length: float = 0.5
    lm: str = "line2"
    kinds: tuple = tuple(SCENE_KINDS)
    ratios: tuple = RATIOS
    embeddings: tuple = EMBEDDINGS
    gauss: dict = field(default_factory=lambda: {
        "element": (1, 2, 3, 4, 6, 8, 12, 16, 24, 32),
        "segment": (1, 2, 3, 4, 5, 6, 7, 8),
        "auto": (1, 2, 3, 4, 5, 6, 7, 8)})
    reference_gauss: int = 24
    repeats: int = 5
    threads: int = 1
    memory: bool = True
    thresholds: tuple = (1e-4, 1e-8)
    reference_pairs: int = 6           # beam elements per reference check (adaptive quadrature)
    benchmark_scene: tuple = (20, 1000, 20)
    benchmark_repeats: int = 7
    scaling_points: tuple = (1e3, 1e4, 1e5, 1e6, 1e7)
    startup_cold: bool = True
    seed: int = 2024
    monitor: bool = True               # solution monitor (MonitorProblem) on the study's scenes
    monitor_max_solid_dofs: int = None  # ... only where the solid has at most this many DOFs (None: all)


def preset(name):
    """``"full"`` (``make report``), ``"quick"`` (< 2 minutes here) or ``"tiny"`` (the test suite)."""
    if name == "full":
        return StudyConfig()
    if name == "quick":
        return StudyConfig(name="quick", cells=6, fibres=6, repeats=3, reference_gauss=16, reference_pairs=3,
                           gauss={"element": (1, 2, 4, 8, 16, 32), "segment": (1, 2, 3, 4, 6, 8),
                                  "auto": (1, 2, 4, 8)},
                           benchmark_repeats=3, scaling_points=(1e3, 1e4, 1e5), startup_cold=False,
                           # monitor on the hex8 scenes only (1029 solid DOFs, < 0.1 s set-up); the hex27 and
                           # tet10 solids (6591 DOFs) measured 6-8 s CPU set-up per scene, over the 2-minute budget
                           monitor_max_solid_dofs=2000)
    if name == "tiny":
        return StudyConfig(name="tiny", cells=3, fibres=2, kinds=("straight fibres, hex8", "curved fibres, tet10"),
                           ratios=(1.0,), repeats=1, memory=False, reference_gauss=12, reference_pairs=2,
                           gauss={"element": (1, 4), "segment": (2, 4), "auto": (2,)},
                           benchmark_scene=(4, 10, 5), benchmark_repeats=1, scaling_points=(1e3, 3e3),
                           startup_cold=False)
    raise ValueError(f"unknown study preset {name!r}; choose full, quick or tiny")


# ------------------------------------------------------------------------------------------ scenes

def build_scene(kind, ratio, embedding, cells=8, fibres=12, fibre_length=0.5, seed=2024):
    """Fibres in the unit cube for one cell of the study.

    Parameters
    ----------
    kind : str
        Key of :data:`SCENE_KINDS`: solid element type, straight or helical fibres, distortion
        of the solid mesh (quadratic elements get curved faces).
    ratio : float
        Beam element length over solid element size h_S = 1 / cells (the fibre's elements:
        ``max(1, round(fibre_length / (ratio h_S)))``).
    embedding : {"embedded", "partly outside"}
        Fibres fully inside (2% margin), or centred on a random face of the cube so that about
        half of every fibre is outside.

    Returns
    -------
    beams : BeamMesh (Hermite), solid : SolidMesh
    """
    element, curved, amplitude = SCENE_KINDS[kind]
    if embedding not in EMBEDDINGS:
        raise ValueError(f"embedding must be one of {EMBEDDINGS}, got {embedding!r}")
    solid = generate.box((0, 0, 0), (1, 1, 1), (cells,) * 3, element)
    if amplitude:
        solid = generate.distort(solid, amplitude, seed=seed)
    m = max(1, int(round(fibre_length * cells / ratio)))
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(fibres, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    radius = 0.1 * fibre_length if curved else 0.0
    reach = 0.5 * fibre_length + radius + 0.02
    centres = reach + (1.0 - 2.0 * reach) * rng.uniform(size=(fibres, 3))
    if embedding == "partly outside":
        face_axis = rng.integers(0, 3, size=fibres)
        centres[np.arange(fibres), face_axis] = rng.integers(0, 2, size=fibres).astype(float)
    phase = rng.uniform(0.0, 2.0 * np.pi, size=fibres)
    positions, tangents = generate._helices(centres, axes, fibre_length, radius, 0.5, phase, m)
    return BeamMesh.hermite(positions, tangents, generate._chain_elements(fibres, m)), solid


# ----------------------------------------------------------------------------------- measurements

def time_assembly(beams, solid, integration, n_gauss, lm="line2", repeats=5, memory=False, warmup=True):
    """Median wall time of ``assemble_mortar`` and its stages; the operators of the last call.

    One untimed call first (JIT compilation or cache loading; skipped with ``warmup=False``
    when the kernels are known to be compiled). With ``memory``, one more call
    under ``tracemalloc`` gives the peak of Python/NumPy allocations (bytes) during a call:
    allocated, not necessarily touched, memory (``np.empty`` buffers count in full).

    Returns
    -------
    record : dict
        ``time_s`` (median), ``min_s``, ``stages_s`` (median per stage), ``points``,
        ``segments``, ``peak_bytes`` (or None).
    ops : MortarOperators
    """
    if warmup:
        assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
    peak = None
    if memory:
        tracemalloc.start()
        try:
            assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    times, stages = [], {k: [] for k in STAGES}
    ops = None
    for _ in range(max(1, repeats)):
        ops = None          # at most one result alive: large scenes stay within memory
        t0 = time.perf_counter()
        ops = assemble_mortar(beams, solid, integration=integration, n_gauss=n_gauss, lm=lm)
        times.append(time.perf_counter() - t0)
        for k, v in _stages(ops.timings).items():
            stages[k].append(v)
    record = {"time_s": statistics.median(times), "min_s": min(times),
              "stages_s": {k: statistics.median(v) for k, v in stages.items()},
              "points": ops.n_integration_points, "segments": len(ops.segments), "peak_bytes": peak}
    return record, ops


def operator_errors(ops, reference):
    """Errors of D, M and κ against ``reference`` (same scene and LM type).

    Returns ``{"D_fro", "M_fro", "D_max", "M_max", "kappa_max"}``: relative Frobenius norm of the
    difference, and the worst entry over the largest entry of the reference.
    """
    out = {}
    for name in ("D", "M"):
        A, B = getattr(ops, name).tocsr(), getattr(reference, name).tocsr()
        diff = (A - B).tocoo()
        ref_norm = math.sqrt(float(B.multiply(B).sum()))
        ref_max = float(abs(B).max()) if B.nnz else 0.0
        d_norm = math.sqrt(float((diff.data ** 2).sum()))
        d_max = float(np.abs(diff.data).max()) if diff.nnz else 0.0
        out[f"{name}_fro"] = d_norm / ref_norm if ref_norm > 0 else d_norm
        out[f"{name}_max"] = d_max / ref_max if ref_max > 0 else d_max
    k_ref = np.abs(reference.kappa).max()
    out["kappa_max"] = float(np.abs(ops.kappa - reference.kappa).max() / k_ref) if k_ref > 0 else 0.0
    return out


#: the linear problem of the solution monitor (see :class:`MonitorProblem`)
MONITOR_SOLID = {"E": 1.0, "nu": 0.3}
MONITOR_BEAM = {"E": 1000.0, "radius": 0.02}
MONITOR_BODY_FORCE = (0.0, 0.0, -1.0)


class ClampedSolid:
    """The clamped solid of the monitor problem: ``K_SS`` factorised once, flexibility on demand.

    Shared by the :class:`MonitorProblem` of every scene on the same solid mesh (the study's
    scenes of one kind differ in their fibres only), so that the factorisation and the columns
    of the flexibility are computed once per mesh.

    Parameters
    ----------
    K : (n_S, n_S) scipy.sparse matrix
        Stiffness of the solid (all DOFs).
    force : (n_S,) array
        Load on the solid DOFs.
    fixed : (n_S,) bool array
        Clamped DOFs (displacement 0).
    points : (n_nodes, 3) array
        The mesh's nodes (to check that a problem is on the same mesh).

    Attributes
    ----------
    u0 : (n_S,) float64
        ``K_SS⁻¹ f_S``: the solid's displacement without the beams.
    dofs : (n_I,) int64
        Free DOFs whose flexibility columns are known (in the order of ``F``).
    F : (n_I, n_I) float64
        ``(K_SS⁻¹)`` restricted to ``dofs`` (symmetric).
    n_columns_solved : int
        Columns of ``K_SS⁻¹`` computed so far (the cost of this object).
    """

    #: flexibility columns solved per call of the factorisation (bounds the dense temporaries)
    CHUNK = 256

    def __init__(self, K, force, fixed, points):
        from .solvers.linear import _factorize
        self.fixed = np.asarray(fixed, dtype=bool)
        self.points = np.asarray(points)
        self.free = np.flatnonzero(~self.fixed)
        self._lu = _factorize(K.tocsr()[self.free][:, self.free], symmetric_positive=True)
        self.u0 = np.zeros(len(self.fixed))
        self.u0[self.free] = self._lu.solve(np.asarray(force, dtype=np.float64)[self.free])
        self.dofs = np.zeros(0, dtype=np.int64)
        self.F = np.zeros((0, 0))
        self._position = np.full(len(self.fixed), -1, dtype=np.int64)
        self.n_columns_solved = 0

    def flexibility(self, dofs):
        """``F[dofs][:, dofs]`` for free ``dofs``: solves ``K_SS x = e_k`` for the columns not known yet."""
        dofs = np.asarray(dofs, dtype=np.int64)
        if self.fixed[dofs].any():
            raise ValueError("ClampedSolid.flexibility: clamped DOFs have no flexibility (their displacement is 0)")
        new = np.unique(dofs[self._position[dofs] < 0])
        if new.size:
            old = self.dofs
            all_dofs = np.concatenate([old, new])
            F = np.empty((len(all_dofs),) * 2)
            F[: len(old), : len(old)] = self.F
            where = np.searchsorted(self.free, new)
            for start in range(0, len(new), self.CHUNK):              # bounded temporaries (n_S x CHUNK)
                cols = slice(start, min(start + self.CHUNK, len(new)))
                E = np.zeros((len(self.free), cols.stop - cols.start))
                E[where[cols], np.arange(cols.stop - cols.start)] = 1.0
                X = np.zeros((len(self.fixed), E.shape[1]))
                X[self.free] = self._lu.solve(E)                        # K_SS⁻¹ e_new
                F[:, len(old) + cols.start: len(old) + cols.stop] = X[all_dofs]
            self.n_columns_solved += len(new)
            F[len(old):, : len(old)] = F[: len(old), len(old):].T
            block = F[len(old):, len(old):]
            F[len(old):, len(old):] = 0.5 * (block + block.T)           # symmetric to round-off
            self.dofs = all_dofs
            self.F = F
            self._position[new] = len(old) + np.arange(len(new))
        k = self._position[dofs]
        return self.F[np.ix_(k, k)]


class MonitorProblem:
    """The linear problem behind the solution monitor of one study scene.

    The unit cube of the scene, small-strain linear elastic (``E = 1, ν = 0.3``), clamped on
    ``x = 0`` and loaded by its own weight (body force ``(0, 0, -1)``): a cantilever that bends.
    The fibres are torsion-free Hermite beams, ``E_B = 1000`` and radius 0.02 (``EA ≈ 1.26``,
    comparable with the axial stiffness of the cube, so the coupling transfers real force),
    tied to the solid by penalty mortar coupling with ``ε = 1e3 E`` (the library's default).
    The fibres must be straight (the scenes of :data:`MONITOR_KINDS`): curved ones are a
    SceneError of the torsion-free beam.

    The solid and beam stiffness are assembled through :class:`~mortar1d3d.model.Model` (given
    the reference operators, so nothing is integrated again) and the clamped solid is
    factorised once (:class:`ClampedSolid`, shareable between scenes on the same mesh);
    :meth:`displacement` then solves the coupled problem for any operators ``D, M, κ`` of the
    scene with a small dense system (Notes).

    Parameters
    ----------
    beams : BeamMesh (Hermite), solid : SolidMesh
        The scene (:func:`build_scene`).
    reference : MortarOperators
        The study's reference operators of the scene: they choose the monitor point and are
        the operators of the model's own coupling (:attr:`scene`).
    penalty : float, optional
        ε; default ``DEFAULT_PENALTY_FACTOR * E`` (1e3).
    clamped : ClampedSolid, optional
        The factorised solid of another MonitorProblem on the same mesh (``.clamped``).

    Attributes
    ----------
    scene : Scene
        The problem as a scene (:func:`monitor_scene`): ``mortar1d3d.solve`` solves the same
        system with its own operators.
    beam_node, solid_node : int
        The monitor point: the beam node with the largest reference κ (the most coupled one)
        and the free solid node nearest to it.
    clamped : ClampedSolid

    Notes
    -----
    **Why penalty, not Lagrange multipliers.** With multipliers the saddle point is singular
    whenever a variant has fewer independent integration points than LM nodes:
    ``B = [-M, D] = P G`` with ``P`` (LM nodes × points) has rank <= the number of points, so
    element-based integration with one point per beam element (``n_el`` points, ``n_el + 1``
    LM nodes per fibre) has dependent constraint rows. The cheapest variants of the study are
    among those to measure, so the monitor uses the library's default penalty enforcement,
    which is well posed whatever the rank of ``B``. The penalty solution depends on ε, but
    every variant and the reference are solved with the same ε, so the error measures the
    operators alone. What no enforcement fixes is a fibre the coupling does not hold against
    rigid motion at all (:meth:`free_motions`); that unloaded motion is set to zero.

    **Condensation.** With ``λ = ε κ⁻¹ (D u_B − M u_S)`` on the coupled LM rows the penalty
    system reads ``K_SS u_S − Mᵀλ = f_S``, ``K_BB u_B + Dᵀλ = f_B``,
    ``D u_B − M u_S − (κ/ε) λ = 0``. Eliminating ``u_S = u_0 + K_SS⁻¹ Mᵀ λ``
    (``u_0 = K_SS⁻¹ f_S``) leaves, per variant,

        [[K_BB, Dᵀ], [D, −(M F Mᵀ + κ/ε)]] [u_B; λ] = [f_B; M u_0],

    with the solid's flexibility ``F = K_SS⁻¹`` restricted to the DOFs that M reaches. The
    system has beam DOFs + 3 × coupled LM nodes unknowns, a few hundred in the study: dense.
    It is the system that :func:`mortar1d3d.model.solve` solves for :attr:`scene` (tested to
    round-off).
    """

    def __init__(self, beams, solid, reference, penalty=None, clamped=None):
        from .model import Model

        self.scene = monitor_scene(beams, solid, reference, penalty)
        model = Model(self.scene).prepare(operators=[reference])
        self.penalty = model.penalty
        g = model.groups[0]
        n_S = 3 * solid.n_nodes
        if (model.fixed_dofs >= n_S).any():
            raise ValueError("MonitorProblem: the monitor scene fixes beam DOFs; it must fix solid DOFs only")
        z0 = np.zeros(model.n_unknowns)
        force = -model.residual(z0, 1.0, tangent=False)[0]        # dead load − internal forces at rest
        _, K_BB = g.physics.evaluate(np.zeros(g.mesh.n_centreline_dofs), tangent=True)
        self.K_BB = K_BB.toarray()
        self.f_B = force[g.dof_offset: g.dof_offset + g.mesh.n_centreline_dofs]
        if clamped is None:
            fixed = np.zeros(n_S, dtype=bool)
            fixed[model.fixed_dofs] = True
            _, K_SS = model.solid_physics.evaluate(np.zeros(n_S), tangent=True)
            clamped = ClampedSolid(K_SS, force[:n_S], fixed, solid.points)
        elif clamped.points.shape != solid.points.shape or not np.array_equal(clamped.points, solid.points):
            raise ValueError("MonitorProblem: clamped belongs to another solid mesh")
        self.clamped = clamped
        kappa_node = np.asarray(reference.kappa[: beams.n_nodes])       # LM nodes 0..n_nodes-1 = beam nodes
        self.beam_node = int(np.argmax(kappa_node))
        if kappa_node[self.beam_node] <= 0:
            raise ValueError("MonitorProblem: no beam node is coupled in the reference operators")
        free_nodes = np.flatnonzero(~clamped.fixed.reshape(-1, 3).all(axis=1))
        dist = np.linalg.norm(solid.points[free_nodes] - beams.positions[self.beam_node], axis=1)
        self.solid_node = int(free_nodes[np.argmin(dist)])
        self._fibre_modes = self._rigid_modes(g)
        self.n_solves = 0
        self.held = True                 # whether the last solve's coupling held every fibre

    @staticmethod
    def _rigid_modes(group):
        """Per fibre (connected chain of beam elements): its local beam DOFs and an orthonormal
        basis of its rigid-body motions (tangents rotate with it)."""
        from scipy.sparse.csgraph import connected_components

        from .solvers.linear import rigid_body_modes
        mesh = group.mesh
        adjacency = sp.coo_matrix((np.ones(mesh.n_elements), (mesh.elements[:, 0], mesh.elements[:, 1])),
                                  shape=(mesh.n_nodes, mesh.n_nodes))
        n_fibres, label = connected_components(adjacency, directed=False)
        out = []
        for f in range(n_fibres):
            nodes = np.flatnonzero(label == f)
            local = (6 * nodes[:, None] + np.arange(6)).ravel()
            # triplets per node: position, tangent (the layout of the beam DOFs)
            triplets = np.stack([mesh.positions[nodes], mesh.tangents[nodes]], axis=1).reshape(-1, 3)
            R = rigid_body_modes(triplets, np.tile([False, True], len(nodes)))
            U, sv, _ = np.linalg.svd(R, full_matrices=False)
            out.append((local, U[:, sv > 1e-10 * sv[0]]))
        return out

    def free_motions(self, D, kappa):
        """Rigid motions of the fibres that the coupling ``D`` (rows with κ > 0) does not stop.

        Each fibre is held against rigid motion by its coupled LM rows alone (the beam stiffness
        does not resist rigid motions). Where they tie the fibre at one point only (element-based
        integration with a single point inside the solid), it can rotate about that point.

        Returns
        -------
        (n_beam_dofs, k) float64
            Orthonormal columns spanning the free motions (k = 0 if every fibre is held).
        """
        rows = np.flatnonzero(np.repeat(np.asarray(kappa) > 0.0, 3))
        Dc = D.tocsr()[rows]
        held = [np.asarray(Dc[:, local] @ Q) for local, Q in self._fibre_modes]   # the coupling seen by each mode
        scale = max((np.linalg.norm(X, 2) for X in held), default=0.0)
        out = []
        for (local, Q), X in zip(self._fibre_modes, held):
            _, sv, Vt = np.linalg.svd(X, full_matrices=X.shape[0] < X.shape[1])     # all of Vt, U thin
            sv = np.concatenate([sv, np.zeros(Q.shape[1] - len(sv))])
            null = Vt[sv <= 1e-8 * scale]
            if len(null):
                Z = np.zeros((self.K_BB.shape[0], len(null)))
                Z[local] = Q @ null.T
                out.append(Z)
        return np.hstack(out) if out else np.zeros((self.K_BB.shape[0], 0))

    def displacement(self, D, M, kappa):
        """Displacements at the monitor point with operators ``D, M, κ`` of this scene.

        Returns
        -------
        (6,) float64
            ``[u_B, u_S]``: the displacement of :attr:`beam_node` and of :attr:`solid_node`.

        Notes
        -----
        Where the coupling leaves a fibre a free rigid motion (:meth:`free_motions`) the system
        is singular but consistent (the beams carry no load of their own): the solid's
        displacement is unique, the fibre's only up to that motion. The solution without it is
        returned (``Zᵀ u_B = 0`` added as constraints), and :attr:`held` is False.
        """
        kappa = np.asarray(kappa, dtype=np.float64)
        n_B, n_S = self.K_BB.shape[0], len(self.clamped.fixed)
        if D.shape != (3 * len(kappa), n_B) or M.shape != (3 * len(kappa), n_S):
            raise ValueError(f"MonitorProblem.displacement: D {D.shape}, M {M.shape} do not fit this scene "
                             f"({3 * len(kappa)} LM rows, {n_B} beam DOFs, {n_S} solid DOFs)")
        Z = self.free_motions(D, kappa)
        self.held = Z.shape[1] == 0
        rows = np.flatnonzero(np.repeat(kappa > 0.0, 3))
        Dc = D.tocsr()[rows]
        Mc = M.tocsr()[rows]
        reached = np.unique(Mc.indices)
        monitor = 3 * self.solid_node + np.arange(3)
        dofs = np.union1d(reached[~self.clamped.fixed[reached]], monitor)   # clamped columns: u_S = 0
        F = self.clamped.flexibility(dofs)
        MI = Mc[:, dofs]
        MF = np.asarray(MI @ F)                                     # (m, n_I)
        m, k = len(rows), Z.shape[1]
        A = np.zeros((n_B + m + k, n_B + m + k))
        A[:n_B, :n_B] = self.K_BB
        A[n_B:n_B + m, :n_B] = Dc.toarray()
        A[:n_B, n_B:n_B + m] = A[n_B:n_B + m, :n_B].T
        A[n_B:n_B + m, n_B:n_B + m] = -(MI @ MF.T + np.diag(np.repeat(kappa, 3)[rows] / self.penalty))
        A[n_B + m:, :n_B] = Z.T * np.abs(self.K_BB).max()            # scaled like K_BB
        A[:n_B, n_B + m:] = A[n_B + m:, :n_B].T
        rhs = np.concatenate([self.f_B, MI @ self.clamped.u0[dofs], np.zeros(k)])
        y = np.linalg.solve(A, rhs)
        self.n_solves += 1
        u_B, lam = y[:n_B], y[n_B:n_B + m]
        k = np.searchsorted(dofs, monitor)
        u_S = self.clamped.u0[monitor] + MF[:, k].T @ lam
        return np.concatenate([u_B[6 * self.beam_node: 6 * self.beam_node + 3], u_S])


def monitor_scene(beams, solid, reference, penalty=None):
    """The :class:`~mortar1d3d.scene.Scene` of :class:`MonitorProblem` (coupling as ``reference``)."""
    from .scene import Scene
    coupling = {"integration": reference.integration, "n_gauss": int(reference.n_gauss), "lm": reference.lm,
                "enforcement": "penalty"}
    if penalty is not None:
        coupling["penalty"] = float(penalty)
    return Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", **MONITOR_SOLID}},
                 beams=[{"mesh": beams, "model": "torsion_free", "section": dict(MONITOR_BEAM)}],
                 coupling=coupling, dirichlet=[{"on": "solid:x_min"}],
                 load=[{"type": "body", "value": list(MONITOR_BODY_FORCE)}],
                 analysis={"kinematics": "linear", "solver": "direct"}, name="solution monitor")


def solution_monitor(problem, D, M, kappa):
    """Monitor-point displacement of the linear solve with the coupling operators ``D, M, κ``.

    Parameters
    ----------
    problem : MonitorProblem
        The scene's linear problem (stiffness assembled and factorised once).
    D, M : scipy.sparse matrices, kappa : (n_lm,) array
        The operators of one integration variant on the problem's scene.

    Returns
    -------
    (6,) float64
        Displacement of the monitor beam node and of the solid node nearest to it.
    """
    if not isinstance(problem, MonitorProblem):
        raise TypeError(f"solution_monitor: problem must be a MonitorProblem (see MonitorProblem(beams, solid, "
                        f"reference)), got {type(problem).__name__}")
    return problem.displacement(D, M, kappa)


def monitor_error(u, u_ref):
    """Relative error ``|u − u_ref| / |u_ref|`` of the monitor displacements (Euclidean norms; NaN if ``u`` is)."""
    u, u_ref = np.asarray(u, dtype=np.float64), np.asarray(u_ref, dtype=np.float64)
    return float(np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref))


# --------------------------------------------------------------- independent adaptive quadrature

def _hermite(eta, L):
    """Hermite functions and η-derivatives of design.md §2 (own formulas, numpy)."""
    H = np.array([(2 - 3 * eta + eta ** 3) / 4, L / 8 * (1 - eta - eta ** 2 + eta ** 3),
                  (2 + 3 * eta - eta ** 3) / 4, L / 8 * (-1 - eta + eta ** 2 + eta ** 3)])
    dH = np.array([(-3 + 3 * eta ** 2) / 4, L / 8 * (-1 - 2 * eta + 3 * eta ** 2),
                   (3 - 3 * eta ** 2) / 4, L / 8 * (-1 + 2 * eta + 3 * eta ** 2)])
    return H, dH


_LM_NODES = {"line2": (-1.0, 1.0), "line3": (-1.0, 1.0, 0.0), "line4": (-1.0, 1.0, -1.0 / 3.0, 1.0 / 3.0)}


def _lagrange(nodes, eta):
    return np.array([np.prod([(eta - b) / (a - b) for b in nodes if b != a]) for a in nodes])


def _project(module, X, p, xi0, h):
    """Newton for x(ξ) = p in numpy (own iteration; the element module's shape functions)."""
    n = X.shape[0]
    N, dN = np.empty(n), np.empty((n, 3))
    xi = np.array(xi0, dtype=float)
    for _ in range(60):
        module.shape.py_func(xi, N)
        r = p - N @ X
        if np.linalg.norm(r) <= 1e-15 * h:
            break
        module.deriv.py_func(xi, dN)
        xi = xi + np.linalg.solve(X.T @ dN, r)
    return xi


def adaptive_segment_integrals(beams, solid, beam_element, solid_element, eta_a, eta_b, lm="line2", epsrel=1e-13):
    """κ_j, D_jk, M_ja of one segment by adaptive quadrature (``scipy.integrate.quad_vec``).

    Independent of the library's kernels: Hermite functions from design.md §2 in numpy, Lagrange
    multipliers from their nodes, the solid point by a numpy Newton iteration (warm-started
    along the segment). Only the shape functions of the solid element modules are shared (they
    are checked on their own in tests/test_elements.py).

    Returns
    -------
    kappa : (n_phi,), D : (n_phi, 4), M : (n_phi, n_nodes)
    """
    from scipy.integrate import quad_vec

    from .elements.solid.dispatch import BY_CODE, SOLID_MODULES

    if beams.element_type.name != "hermite":
        raise ValueError("adaptive_segment_integrals: Hermite beams only")
    d = BY_CODE[int(solid.element_codes[solid_element])]
    module = SOLID_MODULES[d.name]
    X = solid.points[solid.connectivity[solid_element, : d.n_nodes]]
    h = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    n1, n2 = beams.elements[beam_element]
    q = np.array([beams.positions[n1], beams.tangents[n1], beams.positions[n2], beams.tangents[n2]])
    L = beams.lengths[beam_element]
    nodes = _LM_NODES[lm]
    n_phi = len(nodes)
    N = np.empty(d.n_nodes)
    start = [d.centre.astype(float)]

    def integrand(eta):
        H, dH = _hermite(eta, L)
        r, dr = H @ q, dH @ q
        xi = _project(module, X, r, start[0], h)
        start[0] = xi
        module.shape.py_func(xi, N)
        phi = _lagrange(nodes, eta) * np.linalg.norm(dr)
        return np.concatenate([phi, np.outer(phi, H).ravel(), np.outer(phi, N).ravel()])

    values, _ = quad_vec(integrand, eta_a, eta_b, epsabs=0.0, epsrel=epsrel, norm="max", limit=400)
    return values[:n_phi], values[n_phi:n_phi + 4 * n_phi].reshape(n_phi, 4), values[n_phi + 4 * n_phi:].reshape(n_phi, -1)


def pair_reference_check(beams, solid, beam_elements, n_gauss, lm="line2"):
    """Compare segment-based operators (``n_gauss`` per segment) with adaptive quadrature.

    The chosen beam elements get nodes of their own (a copy of the beam mesh with every element
    detached), so that every LM row belongs to one element and the operators can be compared
    entry by entry with :func:`adaptive_segment_integrals` summed over the element's segments.
    Also checks that interior segment ends lie on a face of their solid element.

    Returns
    -------
    dict
        ``D``, ``M``, ``kappa``: largest entry difference over the largest entry; ``face``:
        largest |distance to the reference element's boundary| of the interior segment ends (parameter
        units); ``segments``: how many segments were integrated.
    """
    from .elements.multiplier import multiplier
    from .elements.solid.dispatch import BY_CODE, SOLID_MODULES

    beam_elements = np.atleast_1d(np.asarray(beam_elements, dtype=np.int64))
    nodes = beams.elements[beam_elements].ravel()
    sub = BeamMesh.hermite(beams.positions[nodes], beams.tangents[nodes],
                           np.arange(2 * len(beam_elements)).reshape(-1, 2))
    ops = assemble_mortar(sub, solid, integration="segment", n_gauss=n_gauss, lm=lm)
    lm_type = multiplier(lm)
    index, n_lm = lm_numbering(sub, lm_type)
    columns = sub.function_columns()
    D = np.zeros((n_lm, sub.n_centreline_dofs // 3))
    M = np.zeros((n_lm, solid.n_nodes))
    kappa = np.zeros(n_lm)
    face = 0.0
    for seg in ops.segments:
        e, s = int(seg["beam_element"]), int(seg["solid_element"])
        k, De, Me = adaptive_segment_integrals(sub, solid, e, s, seg["eta_start"], seg["eta_end"], lm)
        d = BY_CODE[int(solid.element_codes[s])]
        conn = solid.connectivity[s, : d.n_nodes]
        for j in range(lm_type.n_functions):
            kappa[index[e, j]] += k[j]
            D[index[e, j], columns[e]] += De[j]
            M[index[e, j], conn] += Me[j]
        X = solid.points[conn]
        h = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
        for eta in (seg["eta_start"], seg["eta_end"]):
            if -1.0 < eta < 1.0:
                H, _ = _hermite(eta, sub.lengths[e])
                q = np.array([sub.positions[sub.elements[e, 0]], sub.tangents[sub.elements[e, 0]],
                              sub.positions[sub.elements[e, 1]], sub.tangents[sub.elements[e, 1]]])
                xi = _project(SOLID_MODULES[d.name], X, H @ q, d.centre, h)
                dist = np.abs(xi).max() - 1.0 if d.family == "hex" else max(-xi.min(), xi.sum() - 1.0)
                face = max(face, abs(dist))
    D_lib = ops.D.toarray()[0::3, 0::3]
    M_lib = ops.M.toarray()[0::3, 0::3]
    return {"D": float(np.abs(D_lib - D).max() / np.abs(D).max()),
            "M": float(np.abs(M_lib - M).max() / np.abs(M).max()),
            "kappa": float(np.abs(ops.kappa - kappa).max() / np.abs(kappa).max()),
            "face": face, "segments": len(ops.segments)}


# ------------------------------------------------------------------------------------------- study

def _set_threads(threads):
    import numba
    default = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    return default


def study_scene(beams, solid, config, progress=None, monitor=False, clamped=None):
    """All variants of ``config`` on one scene: list of records (timing + errors vs the reference).

    With ``monitor``, every variant's operators are also solved with the scene's
    :class:`MonitorProblem` (``clamped``: a :class:`ClampedSolid` of the same mesh to reuse):
    each record gets ``u_err`` (:func:`monitor_error` against the reference operators' solution;
    None without ``monitor``) and ``u_free`` (the variant left a fibre a free rigid motion,
    :meth:`MonitorProblem.free_motions`).

    Returns
    -------
    records : list of dict
    info : dict
        Reference and scene sizes; ``monitor``: the monitor point, reference displacement and
        the monitor's cost (``setup_s``, ``solve_s``: wall time of the set-up and of all the
        solves), or None.
    problem : MonitorProblem or None
    """
    reference = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss, lm=config.lm)
    coarser = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss - 4, lm=config.lm)
    problem, u_ref, solve_s, monitor_info = None, None, 0.0, None
    if monitor:
        t0 = time.perf_counter()
        problem = MonitorProblem(beams, solid, reference, clamped=clamped)
        setup_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        u_ref = solution_monitor(problem, reference.D, reference.M, reference.kappa)
        reference_free = not problem.held
        solve_s += time.perf_counter() - t0
    records = []
    for integration in INTEGRATIONS:
        for n in config.gauss.get(integration, ()):
            rec, ops = time_assembly(beams, solid, integration, n, config.lm, config.repeats, config.memory)
            rec.update(integration=integration, n_gauss=n, **operator_errors(ops, reference), u_err=None)
            if problem is not None:
                t0 = time.perf_counter()
                rec["u_err"] = monitor_error(solution_monitor(problem, ops.D, ops.M, ops.kappa), u_ref)
                rec["u_free"] = not problem.held
                solve_s += time.perf_counter() - t0
            records.append(rec)
            if progress:
                u = "" if rec["u_err"] is None else f"  u {rec['u_err']:.1e}"
                progress(f"    {integration:8s} n={n:2d}: {rec['time_s'] * 1e3:8.2f} ms  "
                         f"D {rec['D_fro']:.1e}  M {rec['M_fro']:.1e}{u}")
    if problem is not None:
        monitor_info = {"beam_node": problem.beam_node, "solid_node": problem.solid_node,
                        "u_ref": [float(x) for x in u_ref], "reference_free": reference_free,
                        "setup_s": setup_s, "solve_s": solve_s,
                        "solves": problem.n_solves, "solid_columns": problem.clamped.n_columns_solved,
                        "solid_dofs": 3 * solid.n_nodes}
    self_check = operator_errors(coarser, reference)
    return records, {"reference_gauss": config.reference_gauss,
                     "reference_vs_coarser": max(self_check["D_fro"], self_check["M_fro"]),
                     "points": reference.n_integration_points, "segments": len(reference.segments),
                     "beam_elements": beams.n_elements, "solid_elements": solid.n_elements,
                     "embedded_length": reference.embedded_length, "beam_length": reference.beam_length,
                     "monitor": monitor_info}, problem


def reference_checks(config, progress=None):
    """Adaptive-quadrature checks of the reference rule on a few beam elements per scene kind."""
    out = {}
    for kind in config.kinds:
        beams, solid = build_scene(kind, 1.0, "partly outside", config.cells, config.fibres, config.fibre_length,
                                   config.seed)
        ops = assemble_mortar(beams, solid, integration="segment", n_gauss=config.reference_gauss, lm=config.lm)
        # the beam elements cut most often: the hardest ones for the reference rule
        cuts = np.bincount(ops.segments["beam_element"], minlength=beams.n_elements)
        chosen = np.argsort(-cuts, kind="stable")[: config.reference_pairs]
        t0 = time.perf_counter()
        out[kind] = pair_reference_check(beams, solid, chosen, config.reference_gauss, config.lm)
        if progress:
            r = out[kind]
            progress(f"  reference check {kind}: {r['segments']} segments, D {r['D']:.1e} M {r['M']:.1e} "
                     f"kappa {r['kappa']:.1e} ({time.perf_counter() - t0:.1f} s)")
    return out


def auto_target(config, progress=None):
    """Auto vs element- and segment-based on the benchmark scene (interleaved repeats, n_gauss 4)."""
    beams, solid = generate.fibre_cube(*config.benchmark_scene)
    times = {k: [] for k in INTEGRATIONS}
    stages = {k: [] for k in INTEGRATIONS}
    ops = {}
    for k in INTEGRATIONS:           # untimed: JIT / cache
        assemble_mortar(beams, solid, integration=k, n_gauss=4)
    for _ in range(max(1, config.benchmark_repeats)):
        for k in INTEGRATIONS:
            t0 = time.perf_counter()
            ops[k] = assemble_mortar(beams, solid, integration=k, n_gauss=4)
            times[k].append(time.perf_counter() - t0)
            stages[k].append(_stages(ops[k].timings))
    reference = assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    out = {"scene": list(config.benchmark_scene), "n_gauss": 4, "repeats": config.benchmark_repeats}
    for k in INTEGRATIONS:
        out[k] = {"time_s": statistics.median(times[k]), "points": ops[k].n_integration_points,
                  "stages_s": {s: statistics.median(t[s] for t in stages[k]) for s in STAGES},
                  **operator_errors(ops[k], reference)}
    out["auto_over_element"] = out["auto"]["time_s"] / out["element"]["time_s"]
    out["segment_over_element"] = out["segment"]["time_s"] / out["element"]["time_s"]
    out["auto_diagnostics"] = {k: int(v) for k, v in ops["auto"].diagnostics.items()}
    if progress:
        progress(f"  auto/element time {out['auto_over_element']:.2f}, segment/element "
                 f"{out['segment_over_element']:.2f}; auto M error {out['auto']['M_fro']:.1e}")
    return out


def scaling(config, progress=None):
    """Time and memory of segment-based assembly (n_gauss 4) of fibre_cube(20, F, 20) vs points."""
    per_fibre = None
    rows = []
    for target in config.scaling_points:
        if per_fibre is None:
            b, s = generate.fibre_cube(20, 10, 20)
            per_fibre = assemble_mortar(b, s, integration="segment", n_gauss=4).n_integration_points / 10
        fibres = max(1, int(round(target / per_fibre)))
        beams, solid = generate.fibre_cube(20, fibres, 20)
        repeats = 3 if target <= 1e6 else 1
        # the first (smallest) size compiles; larger ones need no untimed call
        rec, ops = time_assembly(beams, solid, "segment", 4, repeats=repeats, memory=config.memory,
                                 warmup=not rows)
        rec.update(target=target, fibres=fibres)
        rows.append(rec)
        del beams, solid, ops
        if progress:
            mem = "" if rec["peak_bytes"] is None else f", peak {rec['peak_bytes'] / 2**20:.0f} MiB"
            progress(f"  {rec['points']:>9d} points: {rec['time_s'] * 1e3:9.1f} ms{mem}")
    pts = np.array([r["points"] for r in rows], dtype=float)
    t = np.array([r["time_s"] for r in rows])
    fit = {"time_slope": float(np.polyfit(np.log10(pts), np.log10(t), 1)[0]) if len(rows) > 1 else None}
    big = pts >= 1e4
    if big.sum() >= 2:
        fit["time_slope_from_1e4"] = float(np.polyfit(np.log10(pts[big]), np.log10(t[big]), 1)[0])
    if config.memory and len(rows) > 1:
        m = np.array([r["peak_bytes"] for r in rows], dtype=float)
        fit["memory_slope"] = float(np.polyfit(np.log10(pts), np.log10(m), 1)[0])
        fit["bytes_per_point_largest"] = float(m[-1] / pts[-1])
    return {"rows": rows, "fit": fit}


STARTUP_CODE = ("import time; t=time.perf_counter(); import mortar1d3d as m; b,s=m.generate.fibre_cube(3,2,3); "
                "[m.assemble_mortar(b,s,integration=i) for i in ('segment','element','auto')]; "
                "print(time.perf_counter()-t)")


def startup(cold=True):
    """Import + tiny assembly (segment, element, auto) in a fresh process: cold and warm cache.

    Cold: ``NUMBA_CACHE_DIR`` pointing to an empty directory (every kernel compiles); warm: the
    same directory again. Without ``cold``, only a warm start with the default cache directory
    (filled by this process).
    """
    root = Path(__file__).resolve().parent.parent
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))

    def run(env):
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", STARTUP_CODE], env=env, capture_output=True, text=True,
                             timeout=1800, cwd=str(root))
        wall = time.perf_counter() - t0
        if out.returncode != 0:
            raise RuntimeError(f"start-up subprocess failed: {out.stderr[-2000:]}")
        return {"in_process_s": float(out.stdout.strip().splitlines()[-1]), "wall_s": wall}

    result = {}
    if cold:
        cache = tempfile.mkdtemp(prefix="mortar1d3d-cold-")
        try:
            env_cold = dict(env, NUMBA_CACHE_DIR=cache)
            result["cold"] = run(env_cold)
            result["warm"] = run(env_cold)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    else:
        result["warm"] = run(env)
    return result


def run_study(config, progress=print):
    """Run every part of the study; a JSON-able dict of all measured numbers."""
    import numba

    progress = progress or (lambda *_: None)
    t_start = time.perf_counter()
    default = _set_threads(config.threads)
    try:
        progress(f"study '{config.name}': {len(config.kinds)} kinds x {len(config.ratios)} ratios x "
                 f"{len(config.embeddings)} embeddings, {config.threads} thread(s)")
        scenes = []
        for kind in config.kinds:
            clamped = None      # one factorised solid per kind: the scenes of a kind share the mesh
            for ratio in config.ratios:
                for embedding in config.embeddings:
                    progress(f"  {kind}, h_B/h_S = {ratio:g}, {embedding}")
                    beams, solid = build_scene(kind, ratio, embedding, config.cells, config.fibres,
                                               config.fibre_length, config.seed)
                    monitor = config.monitor and kind in MONITOR_KINDS and (
                        config.monitor_max_solid_dofs is None or 3 * solid.n_nodes <= config.monitor_max_solid_dofs)
                    records, info, problem = study_scene(beams, solid, config, monitor=monitor, clamped=clamped)
                    if problem is not None:
                        clamped = problem.clamped
                        m = info["monitor"]
                        progress(f"    monitor: set-up {m['setup_s']:.2f} s, {m['solves']} solves "
                                 f"{m['solve_s']:.2f} s")
                    scenes.append({"kind": kind, "ratio": ratio, "embedding": embedding, **info,
                                   "records": records})
        progress("reference rule against adaptive quadrature")
        checks = reference_checks(config, progress)
        progress(f"auto target on fibre_cube{tuple(config.benchmark_scene)}")
        target = auto_target(config, progress)
        progress("scaling")
        scale = scaling(config, progress)
        progress("start-up in fresh processes" + (" (cold + warm)" if config.startup_cold else " (warm)"))
        start = startup(cold=config.startup_cold)
        threads_used = numba.get_num_threads()
    finally:
        numba.set_num_threads(default)
    return {"config": asdict(config), "scenes": scenes, "reference_checks": checks, "auto_target": target,
            "scaling": scale, "startup": start,
            "machine": _machine(threads_used), "study_s": time.perf_counter() - t_start}


def _machine(threads):
    import numba
    try:
        load = os.getloadavg()
    except OSError:
        load = None
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10,
                                cwd=str(Path(__file__).resolve().parent)).stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "python": platform.python_version(), "numba": numba.__version__, "numpy": np.__version__,
            "platform": platform.platform(), "cpus": os.cpu_count(), "threads": threads,
            "load_average": list(load) if load else None, "commit": commit}


# ------------------------------------------------------------------------------------------ report

def _err(rec):
    return max(rec["D_fro"], rec["M_fro"])


def _u_err(rec):
    return rec.get("u_err")


def _cheapest(records, integration, threshold, error=_err):
    """Record with the fewest Gauss points of one integration whose error (default: of D and M)
    is <= threshold (or None).

    Fewest points rather than least time: the error of a rule does not depend on the machine load.
    """
    ok = [r for r in records if r["integration"] == integration and error(r) is not None and error(r) <= threshold]
    return min(ok, key=lambda r: r["n_gauss"]) if ok else None


#: how the sentences name the integrations
_LABEL = {"element": "element-based integration", "segment": "segment-based", "auto": "auto"}


def _headline_scene(scenes, kind):
    """The scene of ``kind`` the threshold sentences quote: h_B/h_S = 1 if there is one (or None)."""
    sel = [s for s in scenes if s["kind"] == kind]
    return next((s for s in sel if s["ratio"] == 1.0), sel[0] if sel else None)


def _reach(records, integration, threshold, error):
    """(cheapest record of ``integration`` with ``error`` <= threshold or None, its most accurate record)."""
    recs = [r for r in records if r["integration"] == integration and error(r) is not None]
    if not recs:
        return None, None
    return _cheapest(records, integration, threshold, error), min(recs, key=error)


def _fmt_e(x):
    return "0" if x == 0 else f"{x:.1e}"


def sentences(results):
    """Plain sentences generated from the measured numbers."""
    out = []
    cfg = results["config"]
    for kind in cfg["kinds"]:
        scene = _headline_scene(results["scenes"], kind)
        if scene is None:
            continue
        for threshold in cfg["thresholds"]:
            parts = []
            for integration in INTEGRATIONS:
                best, closest = _reach(scene["records"], integration, threshold, _err)
                if closest is None:
                    continue
                if best is None:
                    parts.append(f"{_LABEL[integration]} does not reach it with up to "
                                 f"{max(cfg['gauss'][integration])} points per "
                                 f"{'beam element' if integration == 'element' else 'segment'} "
                                 f"(best {_fmt_e(_err(closest))} with n = {closest['n_gauss']})")
                else:
                    parts.append(f"{_LABEL[integration]} needs n = {best['n_gauss']} ({best['points']} points, "
                                 f"{best['time_s'] * 1e3:.2f} ms)")
            out.append(f"To reach a D/M error of {threshold:.0e} on {kind} (h_B/h_S = {scene['ratio']:g}, "
                       f"{scene['embedding']}), " + "; ".join(parts) + ".")
    for kinds, label in ((["straight fibres, hex8"], "straight fibres in hex8"),
                         ([k for k in cfg["kinds"] if k != "straight fibres, hex8"], "curved fibres in curved elements")):
        ratios = []
        for scene in results["scenes"]:
            if scene["kind"] not in kinds:
                continue
            seg = {r["n_gauss"]: r["time_s"] for r in scene["records"] if r["integration"] == "segment"}
            ratios += [r["time_s"] / seg[r["n_gauss"]] for r in scene["records"]
                       if r["integration"] == "auto" and r["n_gauss"] in seg]
        if ratios:
            out.append(f"On {label}, \"auto\" takes a median {statistics.median(ratios):.2f}x the time of "
                       f"segment-based integration with the same n (range {min(ratios):.2f}-{max(ratios):.2f} over "
                       f"{len(ratios)} scene/n pairs)" + (", with the exact rule at any n" if "straight" in label else
                                                         ", with the same points (no affine elements to exploit)")
                       + ".")
    out += monitor_sentences(results)
    t = results["auto_target"]
    verdict = "meets" if t["auto_over_element"] <= 1.3 else "misses"
    out.append(f"On the benchmark scene fibre_cube{tuple(t['scene'])} with n_gauss = 4, \"auto\" takes "
               f"{t['auto']['time_s'] * 1e3:.0f} ms, {t['auto_over_element']:.2f}x the element-based "
               f"{t['element']['time_s'] * 1e3:.0f} ms (segment-based: {t['segment_over_element']:.2f}x), with a "
               f"D/M error of {_fmt_e(_err(t['auto']))} against segment-based with 8 points (element-based: "
               f"{_fmt_e(_err(t['element']))}); it {verdict} the target of 1.3x.")
    fit = results["scaling"]["fit"]
    rows = results["scaling"]["rows"]
    if fit.get("time_slope") is not None:
        out.append(f"From {rows[0]['points']:.1e} to {rows[-1]['points']:.1e} integration points the "
                   f"segment-based assembly time grows with slope {fit['time_slope']:.2f} on a log-log scale"
                   + (f" ({fit['time_slope_from_1e4']:.2f} from 1e4 points on)" if "time_slope_from_1e4" in fit
                      else "") + ".")
    st = results["startup"]
    if "cold" in st:
        out.append(f"A fresh process needs {st['cold']['in_process_s']:.1f} s to import and assemble a tiny "
                   f"scene with an empty kernel cache (compilation), {st['warm']['in_process_s']:.2f} s with the "
                   "cache filled.")
    else:
        out.append(f"A fresh process with a filled kernel cache imports and assembles a tiny scene in "
                   f"{st['warm']['in_process_s']:.2f} s (cold start: run the full report).")
    return out


def monitor_sentences(results):
    """Sentences on the solution monitor: how the displacement error follows the D/M error."""
    cfg = results["config"]
    scenes = [sc for sc in results["scenes"] if sc.get("monitor")]
    if not scenes:
        return ["The solution monitor did not run on any scene of this study (see Method)."]
    out = []
    threshold = cfg["thresholds"][0]
    for kind in cfg["kinds"]:
        scene = _headline_scene(scenes, kind)
        if scene is None:
            continue
        parts = []
        for integration in INTEGRATIONS:
            best, closest = _reach(scene["records"], integration, threshold, _u_err)
            if closest is None:
                continue
            if best is None:
                parts.append(f"{_LABEL[integration]} does not reach it (best {_fmt_e(closest['u_err'])} with "
                             f"n = {closest['n_gauss']})")
            else:
                parts.append(f"{_LABEL[integration]} needs n = {best['n_gauss']} (D/M error there "
                             f"{_fmt_e(_err(best))})")
        out.append(f"To reach a monitor displacement error of {threshold:.0e} on {kind} (h_B/h_S = "
                   f"{scene['ratio']:g}, {scene['embedding']}), " + "; ".join(parts) + ".")
    pairs = [(r["u_err"], _err(r)) for sc in scenes for r in sc["records"] if r["u_err"] is not None
             and _err(r) > 1e-12]
    if pairs:
        ratios = [u / e for u, e in pairs]
        below = sum(x <= 1.0 for x in ratios)
        u_log, e_log = np.log10([u for u, _ in pairs]), np.log10([e for _, e in pairs])
        slope = float(np.polyfit(e_log, u_log, 1)[0]) if len(pairs) > 2 and np.ptp(e_log) > 0 else None
        text = (f"Where the operators are inexact (D/M error > 1e-12: {len(pairs)} variant/scene pairs on "
                f"{len(scenes)} scenes), the monitor displacement error is a median {statistics.median(ratios):.2g}x "
                f"the D/M error (range {min(ratios):.2g}-{max(ratios):.2g}x); it is below the D/M error in {below} "
                f"of the {len(pairs)} pairs")
        if slope is not None:
            text += (f", and a log-log fit over all pairs gives u err ~ (D/M error)^{slope:.2f} "
                     "(1 would mean: proportional)")
        out.append(text + ".")
    exact = [r["u_err"] for sc in scenes for r in sc["records"] if r["u_err"] is not None and _err(r) <= 1e-12]
    if exact:
        out.append(f"Variants with operators exact to round-off (D/M error <= 1e-12, {len(exact)} pairs) give "
                   f"displacements within {_fmt_e(max(exact))} of the reference solution.")
    free = [(sc, r) for sc in scenes for r in sc["records"] if r.get("u_free")]
    ref_free = [sc for sc in scenes if sc["monitor"].get("reference_free")]
    if free or ref_free:
        counts = {}
        for _, r in free:
            counts.setdefault(r["integration"], set()).add(int(r["n_gauss"]))
        which = [f"{name}-based n ∈ {{{', '.join(str(n) for n in sorted(ns))}}}" for name, ns in sorted(counts.items())]
        out.append(f"In {len(free)} variant/scene pair(s) on "
                   f"{len({id(sc) for sc, _ in free})} scene(s)" + (f" ({'; '.join(which)})" if which else "")
                   + (f" and in the reference solution of {len(ref_free)} scene(s)" if ref_free else "")
                   + " the coupling leaves some fibre a free rigid motion (held at one point, which it can turn "
                   "about); the fibre's free motion is set to zero there (`*` in the tables).")
    n_all = len(results["scenes"])
    straight = [sc for sc in results["scenes"] if sc["kind"] in MONITOR_KINDS]
    if len(scenes) < n_all:
        why = ["straight fibres only: the torsion-free beam needs initially straight centrelines, and curved "
               "fibres wait for a beam with a material frame (see Method)"]
        if len(scenes) < len(straight):
            cost = [sc["monitor"]["setup_s"] for sc in scenes]
            why.append(f"solids with at most {cfg['monitor_max_solid_dofs']} DOFs; its set-up took "
                       f"{min(cost):.2f}-{max(cost):.2f} s per scene there, the larger solids cost a factorisation "
                       "and a flexibility column per coupled solid DOF each")
        out.append(f"The monitor ran on {len(scenes)} of {n_all} scenes ({'; '.join(why)}).")
    return out


def _error_time_grid(plt, matplotlib, scenes, kinds, ratios, error, ylabel, floor, pareto=False):
    """One log-log panel per (kind, ratio): ``error`` of each record against its median time, a
    curve per integration and embedding (records without the error are left out); ``pareto``
    marks the Pareto-optimal points."""
    colours = {"element": "tab:blue", "segment": "tab:orange", "auto": "tab:green"}
    fig, axes = plt.subplots(len(kinds), len(ratios), figsize=(4.2 * len(ratios), 3.4 * len(kinds)),
                             squeeze=False, sharey=True)
    for i, kind in enumerate(kinds):
        for j, ratio in enumerate(ratios):
            ax = axes[i, j]
            for scene in scenes:
                if scene["kind"] != kind or scene["ratio"] != ratio:
                    continue
                style = "-" if scene["embedding"] == "embedded" else "--"
                for integration in INTEGRATIONS:
                    recs = [r for r in scene["records"] if r["integration"] == integration and error(r) is not None]
                    if not recs:
                        continue
                    x = [r["time_s"] * 1e3 for r in recs]
                    y = [max(error(r), floor) for r in recs]
                    ax.loglog(x, y, style, marker="o", ms=3, color=colours[integration],
                              label=f"{integration}, {scene['embedding']}")
                    if pareto:
                        front = _pareto(x, y)
                        ax.loglog([x[k] for k in front], [y[k] for k in front], "s", ms=6, mfc="none",
                                  color=colours[integration])
            ax.set_title(f"{kind}, h_B/h_S = {ratio:g}", fontsize=9)
            ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            ax.grid(True, which="major", alpha=0.3)
            if i == len(kinds) - 1:
                ax.set_xlabel("median assemble_mortar time [ms]")
            if j == 0:
                ax.set_ylabel(ylabel)
    axes[0, 0].legend(fontsize=7)
    return fig


def _save(plt, fig, out, name):
    """Lay out, write ``out/name`` as PNG, close; returns ``name``."""
    fig.tight_layout()
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return name


def _plots(results, out):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        return {}
    files = {}
    cfg = results["config"]
    kinds, ratios = cfg["kinds"], cfg["ratios"]
    floor = 1e-17
    fig = _error_time_grid(plt, matplotlib, results["scenes"], kinds, ratios, _err,
                           "max(rel. Frobenius error of D, M)", floor, pareto=True)
    fig.suptitle("Error vs time per variant\n(squares: Pareto-optimal; solid: embedded, dashed: partly outside; "
                 "errors < 1e-17 drawn at 1e-17)", fontsize=9)
    files["pareto"] = _save(plt, fig, out, "pareto.png")

    monitored = [sc for sc in results["scenes"] if sc.get("monitor")]
    if monitored:
        mkinds = [k for k in kinds if any(sc["kind"] == k for sc in monitored)]
        fig = _error_time_grid(plt, matplotlib, monitored, mkinds, ratios, _u_err, "monitor displacement error",
                               floor)
        fig.suptitle("Solution error vs assembly time per variant: |u - u_ref| / |u_ref| at the monitor point\n"
                     "(solid: embedded, dashed: partly outside; errors < 1e-17 drawn at 1e-17)", fontsize=9)
        files["monitor"] = _save(plt, fig, out, "monitor.png")

    # stage breakdown on the benchmark scene
    t = results["auto_target"]
    fig, ax = plt.subplots(figsize=(6.5, 3.6))
    bottom = np.zeros(len(INTEGRATIONS))
    for stage in STAGES:
        v = np.array([t[k]["stages_s"][stage] * 1e3 for k in INTEGRATIONS])
        ax.bar(INTEGRATIONS, v, bottom=bottom, label=stage)
        bottom += v
    ax.set_ylabel("median time [ms]")
    ax.set_title(f"Stages of assemble_mortar, fibre_cube{tuple(t['scene'])}, n_gauss = 4", fontsize=10)
    ax.legend(fontsize=8)
    files["stages"] = _save(plt, fig, out, "stages.png")

    rows = results["scaling"]["rows"]
    fig, ax = plt.subplots(1, 2 if cfg["memory"] else 1, figsize=(10 if cfg["memory"] else 5.5, 3.8), squeeze=False)
    pts = np.array([r["points"] for r in rows], dtype=float)
    tt = np.array([r["time_s"] for r in rows])
    ax[0, 0].loglog(pts, tt, "o-", label="measured")
    fit = results["scaling"]["fit"]
    if fit.get("time_slope") is not None:
        c = np.polyfit(np.log10(pts), np.log10(tt), 1)
        ax[0, 0].loglog(pts, 10 ** np.polyval(c, np.log10(pts)), "k--", label=f"fit, slope {c[0]:.2f}")
    ax[0, 0].set_xlabel("integration points")
    ax[0, 0].set_ylabel("median time [s]")
    ax[0, 0].legend(fontsize=8)
    ax[0, 0].grid(True, which="major", alpha=0.3)
    if cfg["memory"]:
        m = np.array([r["peak_bytes"] for r in rows], dtype=float) / 2 ** 20
        ax[0, 1].loglog(pts, m, "o-", color="tab:red", label="tracemalloc peak")
        if fit.get("memory_slope") is not None:
            c = np.polyfit(np.log10(pts), np.log10(m), 1)
            ax[0, 1].loglog(pts, 10 ** np.polyval(c, np.log10(pts)), "k--", label=f"fit, slope {c[0]:.2f}")
        ax[0, 1].set_xlabel("integration points")
        ax[0, 1].set_ylabel("peak memory [MiB]")
        ax[0, 1].legend(fontsize=8)
        ax[0, 1].grid(True, which="major", alpha=0.3)
    fig.suptitle("Scaling of segment-based assembly (fibre_cube(20, F, 20), n_gauss = 4)", fontsize=10)
    files["scaling"] = _save(plt, fig, out, "scaling.png")
    return files


def _pareto(x, y):
    """Indices of the points not dominated in (time, error), sorted by time."""
    order = sorted(range(len(x)), key=lambda k: (x[k], y[k]))
    front, best = [], math.inf
    for k in order:
        if y[k] < best:
            front.append(k)
            best = y[k]
    return front


def write_report(results, out="report"):
    """Write ``accuracy_vs_time.md``, the PNG plots and ``results.json`` into ``out``; the report's path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = _plots(results, out)
    cfg = results["config"]
    mach = results["machine"]
    L = []
    L.append("# Accuracy vs time of the coupling integration\n")
    L.append(f"Generated by `mortar1d3d bench report{' --quick' if cfg['name'] == 'quick' else ''}` "
             f"(preset `{cfg['name']}`) on {mach['date']}, commit {mach['commit']}; Python {mach['python']}, "
             f"Numba {mach['numba']}, {mach['cpus']} CPUs, {mach['threads']} Numba thread(s) for all timings, "
             f"load average {', '.join(f'{x:.2f}' for x in mach['load_average']) if mach['load_average'] else '?'}. "
             f"The study took {results['study_s']:.0f} s. Timings on a shared machine are noisy; errors are not.\n")
    L.append("## Findings\n")
    for s in sentences(results):
        L.append(f"- {s}")
    L.append("")
    L.append("## Method\n")
    L.append(f"- Scenes: the unit cube with {cfg['cells']}³ cells; {cfg['fibres']} Hermite fibres of length "
             f"{cfg['fibre_length']} (straight, or half a helix turn of radius {0.1 * cfg['fibre_length']:g}); "
             "hex27 and tet10 meshes distorted (amplitude 0.1 of the cell size: curved faces). Beam element length "
             f"h_B over solid element size h_S in {list(cfg['ratios'])}; fibres fully embedded or centred on a face "
             f"of the cube (partly outside). LM interpolation `{cfg['lm']}`.")
    L.append(f"- Cost: median of {cfg['repeats']} calls of `assemble_mortar` after one untimed call (JIT "
             "excluded), stages from `ops.timings`; peak memory: `tracemalloc` peak of one more call (NumPy "
             "allocations, counted in full even where pages are never touched, e.g. the segmentation's "
             "crossing buffer; scratch buffers inside the kernels are not seen).")
    L.append(f"- Accuracy: relative Frobenius error and worst entry (over the largest entry) of D and M against "
             f"segment-based integration with {cfg['reference_gauss']} points per segment. `auto` uses the minimal "
             "exact Gauss rule on segments where the integrand is a polynomial (straight beams in affine "
             "elements), so its error there does not depend on n.")
    mon_scope = "the straight-fibre scenes" + ("" if cfg.get("monitor_max_solid_dofs") is None else
                                               f" whose solid has at most {cfg['monitor_max_solid_dofs']} DOFs")
    L.append("- Solution error (`u err`): a linear solve with each variant's operators "
             "(`mortar1d3d.study.MonitorProblem`): the cube, small-strain linear elastic (E = 1, ν = 0.3), "
             "clamped on x = 0 and bent by its own weight (body force (0, 0, -1)); the fibres torsion-free "
             "Hermite beams with E = 1000 and radius 0.02 (EA ≈ 1.26, as stiff axially as the cube, so the "
             "coupling carries real force), tied by penalty mortar coupling (ε = 1e3 E, the library default; "
             "with Lagrange multipliers the saddle point is singular for variants with fewer integration "
             "points than LM nodes, e.g. element-based n = 1). The monitor point is the beam node with the "
             "largest reference κ and the free solid node nearest to it; `u err` = |u - u_ref| / |u_ref| over "
             "both nodes' displacements, u_ref from the reference operators. The solid is factorised once per "
             "mesh and condensed onto the DOFs the coupling reaches, so each variant costs one small dense "
             "solve. `*`: the variant's coupling leaves some fibre a free rigid motion (a single coupling "
             "point): the unloaded free motion is set to zero. "
             f"Measured on {mon_scope}. Not on curved fibres: the torsion-free beam holds for initially straight "
             "centrelines only (a curved one could change its bending plane at no cost), and a truss would need "
             "the operators of a line centreline, not the Hermite ones measured here, and has no stiffness against "
             "sideways motion where a fibre leaves the cube; curved fibres wait for a beam with a material frame"
             + ("." if cfg.get("monitor", True) else " (switched off in this run).")
             + "\n")
    L.append("## The reference\n")
    L.append("Segment-based integration with the reference Gauss count, compared entry by entry with an "
             "independent adaptive quadrature (`scipy.integrate.quad_vec`, relative tolerance 1e-13, own "
             "Hermite formulas and Newton projection) on the most-cut beam elements of each kind "
             "(h_B/h_S = 1, partly outside); `face` is the largest distance of an interior segment end from "
             "its element's boundary in parameter units.\n")
    L.append("| scene | segments | D | M | κ | face |")
    L.append("|---|---|---|---|---|---|")
    for kind, r in results["reference_checks"].items():
        L.append(f"| {kind} | {r['segments']} | {_fmt_e(r['D'])} | {_fmt_e(r['M'])} | {_fmt_e(r['kappa'])} | "
                 f"{_fmt_e(r['face'])} |")
    L.append("")
    L.append("Per scene, the reference also differs from segment-based integration with 4 fewer points per "
             "segment by `ref vs n-4` in the tables below (an estimate of its own error).\n")
    if "pareto" in files:
        L.append(f"![error vs time]({files['pareto']})\n")
    if "monitor" in files:
        L.append(f"![solution error vs time]({files['monitor']})\n")
    L.append("## Tables\n")
    L.append("Times in ms (median); stages: search / segmentation / integration points / assembly / CSR / "
             "other (certificates, point records). "
             "Errors: relative Frobenius norm (fro) and worst entry (max); `u err`: monitor displacement "
             "error (— where the monitor did not run; `*`: a fibre had a free rigid motion, see Method).\n")
    for scene in results["scenes"]:
        L.append(f"### {scene['kind']}, h_B/h_S = {scene['ratio']:g}, {scene['embedding']}\n")
        L.append(f"{scene['beam_elements']} beam elements, {scene['solid_elements']} solid elements; embedded length "
                 f"{scene['embedded_length']:.4f} of {scene['beam_length']:.4f}; reference: "
                 f"{scene['points']} points on {scene['segments']} segments; ref vs n-4: "
                 f"{_fmt_e(scene['reference_vs_coarser'])}.\n")
        mon = scene.get("monitor")
        if mon:
            L.append(f"Monitor: beam node {mon['beam_node']}, solid node {mon['solid_node']}; |u_ref| = "
                     f"{np.linalg.norm(mon['u_ref']):.4g}" + ("*" if mon.get("reference_free") else "")
                     + f"; set-up {mon['setup_s']:.2f} s, {mon['solves']} solves {mon['solve_s']:.2f} s.\n")
        mem_head = " peak MiB |" if cfg["memory"] else ""
        L.append(f"| integration | n | points | time | stages |{mem_head} D fro | M fro | D max | M max | u err |")
        L.append("|---|---|---|---|---|" + ("---|" if cfg["memory"] else "") + "---|---|---|---|---|")
        for r in scene["records"]:
            st = " / ".join(f"{r['stages_s'][k] * 1e3:.2f}" for k in STAGES)
            mem = f" {r['peak_bytes'] / 2**20:.2f} |" if cfg["memory"] else ""
            u = "—" if not mon or r.get("u_err") is None else _fmt_e(r["u_err"]) + ("*" if r.get("u_free") else "")
            L.append(f"| {r['integration']} | {r['n_gauss']} | {r['points']} | {r['time_s'] * 1e3:.2f} | {st} |"
                     f"{mem} {_fmt_e(r['D_fro'])} | {_fmt_e(r['M_fro'])} | {_fmt_e(r['D_max'])} | "
                     f"{_fmt_e(r['M_max'])} | {u} |")
        L.append("")
    t = results["auto_target"]
    L.append(f"## \"auto\" on the benchmark scene fibre_cube{tuple(t['scene'])}\n")
    L.append(f"n_gauss = 4, medians of {t['repeats']} interleaved calls per variant; errors against "
             "segment-based with 8 points per segment.\n")
    L.append("| integration | points | time ms | " + " | ".join(STAGES) + " | D fro | M fro |")
    L.append("|---|---|---|" + "---|" * len(STAGES) + "---|---|")
    for k in INTEGRATIONS:
        r = t[k]
        L.append(f"| {k} | {r['points']} | {r['time_s'] * 1e3:.1f} | "
                 + " | ".join(f"{r['stages_s'][s] * 1e3:.1f}" for s in STAGES)
                 + f" | {_fmt_e(r['D_fro'])} | {_fmt_e(r['M_fro'])} |")
    L.append("")
    L.append(f"auto / element-based time: **{t['auto_over_element']:.2f}** (target <= 1.3); "
             f"segment-based / element-based: {t['segment_over_element']:.2f}. Auto diagnostics: "
             + ", ".join(f"{k} {v}" for k, v in t["auto_diagnostics"].items()) + ".\n")
    if "stages" in files:
        L.append(f"![stages]({files['stages']})\n")
    L.append("## Scaling\n")
    L.append("Segment-based, n_gauss = 4, fibre_cube(20, F, 20) with F chosen for the target number of points; "
             "median of 3 calls (1 above 1e6 points).\n")
    mem_head = " tracemalloc peak MiB | bytes / point |" if cfg["memory"] else ""
    L.append(f"| fibres | points | time s | points / s |{mem_head}")
    L.append("|---|---|---|---|" + ("---|---|" if cfg["memory"] else ""))
    for r in results["scaling"]["rows"]:
        mem = (f" {r['peak_bytes'] / 2**20:.1f} | {r['peak_bytes'] / r['points']:.0f} |" if cfg["memory"] else "")
        L.append(f"| {r['fibres']} | {r['points']} | {r['time_s']:.4f} | {r['points'] / r['time_s']:.3g} |{mem}")
    fit = results["scaling"]["fit"]
    L.append("")
    L.append("Fitted log-log slopes: " + ", ".join(f"{k} {v:.3g}" for k, v in fit.items() if v is not None) + ".\n")
    if "scaling" in files:
        L.append(f"![scaling]({files['scaling']})\n")
    st = results["startup"]
    L.append("## Start-up\n")
    L.append("Fresh `python -c` process: import + assembly of fibre_cube(3, 2, 3) with segment, element and auto "
             "integration.\n")
    L.append("| cache | in process s | wall s (incl. interpreter) |")
    L.append("|---|---|---|")
    for k in ("cold", "warm"):
        if k in st:
            L.append(f"| {k} | {st[k]['in_process_s']:.2f} | {st[k]['wall_s']:.2f} |")
    if "cold" not in st:
        L.append("\nCold start (empty `NUMBA_CACHE_DIR`) is measured by the full report only.")
    L.append("")
    path = out / "accuracy_vs_time.md"
    path.write_text("\n".join(L) + "\n")
    (out / "results.json").write_text(json.dumps(results, indent=1, default=float) + "\n")
    return path


def make_report(preset_name="full", out="report", progress=print, **overrides):
    """Run the study with a preset (plus field overrides) and write the report; returns its path."""
    config = replace(preset(preset_name), **overrides)
    results = run_study(config, progress=progress)
    path = write_report(results, out)
    if progress:
        progress(f"wrote {path}")
    return path
