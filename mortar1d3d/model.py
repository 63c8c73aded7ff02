"""Model: the operators a :class:`~mortar1d3d.scene.Scene` needs, and nothing else.

Global unknowns ``z = [d_S; d_B(group 0); d_B(group 1); ...; λ]``: solid displacements
(``3*node + i``), then the centreline DOFs of each beam group (beams of one model share a
:class:`BeamMesh` and one set of mortar operators: Hermite ``[r, t]`` per node for
``torsion_free``, positions for ``truss``), then Lagrange multipliers (coupled LM rows) when the
coupling is enforced with Lagrange multipliers.

Every stage that does work increments ``Model.counts[<effect>]`` with the names that
:func:`plan` lists, so that tests can prove what ran.
"""
import math
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .errors import AccuracyWarning, CouplingWarning, LargeDeformationWarning, MeshError, format_ids
from .generate import box as box_mesh
from .mesh import BeamMesh, SolidMesh, zero_length_elements
from .mortar.assemble import assemble_mortar
from .scene import BOX_FACES, Scene, SceneError
from .supports import RotatedBasis, clamp_frame

DEFAULT_PENALTY_FACTOR = 1e3     # ε = 1e3 E_solid when the scene gives no penalty
PENALTY_ROUNDOFF_LIMIT = 1e8     # ε / E_solid above which round-off beats the penalty error (AccuracyWarning)
LINEAR_DISPLACEMENT_LIMIT = 0.1  # max |u| / body size above which a linear result is flagged (LargeDeformationWarning)


@dataclass(frozen=True)
class Effect:
    """One thing :func:`solve` will compute: a stable ``name`` and how often/what exactly."""

    name: str
    when: str
    detail: str = ""

    def __str__(self):
        return f"{self.name:<28} {self.when:<22} {self.detail}"


# --------------------------------------------------------------------------------------------
# beam meshes from curve specifications
# --------------------------------------------------------------------------------------------
def _chord_tangents(points):
    n = len(points)
    zero = zero_length_elements(points, np.column_stack([np.arange(n - 1), np.arange(1, n)]))
    if zero.size:
        raise MeshError(f"beam elements of zero length (consecutive nodes coincide): {format_ids(zero)}")
    d = np.diff(points, axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    t = np.empty_like(points)
    t[0], t[-1] = d[0], d[-1]
    t[1:-1] = d[:-1] + d[1:]
    norm = np.linalg.norm(t[1:-1], axis=1)
    if (norm < 1e-12).any():
        raise MeshError("polyline folds back on itself (opposite consecutive segments)")
    t[1:-1] /= norm[:, None]
    return t


def _curve_functions(curve):
    """(f, df, t0, t1) of a smooth curve spec."""
    if "line" in curve:
        a, b = curve["line"]
        return (lambda t: a + t * (b - a)), (lambda t: b - a), 0.0, 1.0
    if "helix" in curve:
        h = curve["helix"]

        def sample(t):
            t = np.atleast_1d(t)
            pts, tan = [], []
            for ti in t:
                p, d = _helix_point(h, ti)
                pts.append(p)
                tan.append(d)
            return np.array(pts), np.array(tan)
        return (lambda t: sample(t)[0][0]), (lambda t: sample(t)[1][0]), 0.0, 1.0
    return curve["function"], curve["derivative"], float(curve["t"][0]), float(curve["t"][1])


def _helix_point(h, s):
    from .generate import _helix_frame
    e1, e2 = _helix_frame(h["axis"][None, :])
    theta = h["phase"] + 2.0 * math.pi * h["turns"] * s
    p = h["centre"] + (s - 0.5) * h["length"] * h["axis"] + h["radius"] * (math.cos(theta) * e1[0] + math.sin(theta) * e2[0])
    d = h["length"] * h["axis"] + 2.0 * math.pi * h["turns"] * h["radius"] * (math.cos(theta) * e2[0] - math.sin(theta) * e1[0])
    return p, d


def read_mesh_file(path, where):
    """``meshio.read(path)``; any failure becomes a SceneError that names ``where`` and the file."""
    import meshio
    try:
        return meshio.read(path)
    except SystemExit:      # meshio's XML readers call sys.exit on a malformed file
        raise SceneError(f"{where}: cannot read mesh file {str(path)!r} (malformed {Path(path).suffix} file)") from None
    except Exception as exc:
        raise SceneError(f"{where}: cannot read mesh file {str(path)!r}: {type(exc).__name__}: {exc}") from None


def check_solid_nodes(mesh, where):
    """SceneError naming node ids if ``mesh`` has nodes no element uses (their stiffness is zero)
    or distinct nodes at the same place (a crack: the elements on either side do not connect).

    Two nodes coincide when they are closer than 1e-10 of the mesh's bounding-box diagonal.
    """
    used = np.zeros(mesh.n_nodes, dtype=bool)
    used[mesh.connectivity[mesh.connectivity >= 0]] = True
    if not used.all():
        unused = np.flatnonzero(~used)
        raise SceneError(f"{where}: nodes not used by any element: {format_ids(unused)} (remove them)")
    from scipy.spatial import cKDTree
    X = mesh.points
    size = float(np.linalg.norm(np.ptp(X, axis=0)))
    pairs = cKDTree(X).query_pairs(1e-10 * size, output_type="ndarray")
    if len(pairs):
        raise SceneError(f"{where}: duplicate nodes at the same position: {_node_pairs(pairs)}; the elements on either "
                         "side are not connected (merge the duplicates)")


def _node_pairs(pairs, limit=5):
    """``"1 and 12, 4 and 13 (and 2 more pairs)"``: node pairs in a fixed order for messages."""
    pairs = np.sort(np.asarray(pairs), axis=1)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    more = f" (and {len(pairs) - limit} more pairs)" if len(pairs) > limit else ""
    return ", ".join(f"{a} and {b}" for a, b in pairs[:limit]) + more


def check_beam_nodes(mesh, where):
    """SceneError naming node ids if the beam mesh ``mesh`` has nodes no element uses (their
    stiffness is zero: the solve would fail as singular) or two chain ends at the same place (one
    beam split in two pieces that do not connect, the beam counterpart of a crack).

    Coincident nodes elsewhere are allowed: fibres that cross or touch at a node of one of them
    are separate beams on purpose. Two nodes coincide when they are closer than 1e-10 of the
    mesh's bounding-box diagonal.
    """
    used = np.zeros(mesh.n_nodes, dtype=bool)
    used[mesh.elements] = True
    if not used.all():
        raise SceneError(f"{where}: nodes not used by any element: {format_ids(np.flatnonzero(~used))} (remove them)")
    # columns 0 and 1 are the element's end nodes for every beam element type (line3: ends, then middle)
    ends = np.bincount(mesh.elements[:, :2].ravel(), minlength=mesh.n_nodes) == 1
    from scipy.spatial import cKDTree
    X = mesh.positions[ends]
    size = float(np.linalg.norm(np.ptp(mesh.positions, axis=0)))
    pairs = np.flatnonzero(ends)[cKDTree(X).query_pairs(1e-10 * size, output_type="ndarray")] if len(X) > 1 else []
    if len(pairs):
        raise SceneError(f"{where}: beam ends at the same position: {_node_pairs(pairs)}; the elements on either side "
                         "are not connected (use one node there)")


def _read_beam_file(path, hermite, where):
    m = read_mesh_file(path, where)
    lines = [c.data for c in m.cells if c.type == "line"]
    if not lines:
        raise MeshError(f"{path}: no 'line' cells")
    elements = np.vstack(lines)
    if hermite:
        if "tangent" in m.point_data:
            tangents = m.point_data["tangent"]
        else:
            order = np.concatenate([elements[:, 0], elements[-1:, 1]])
            if len(np.unique(order)) != len(order) or not (elements[1:, 0] == elements[:-1, 1]).all():
                raise MeshError(f"{path}: without point data 'tangent' the line cells must form one chain")
            tangents = np.zeros_like(m.points, dtype=float)
            tangents[order] = _chord_tangents(m.points[order].astype(float))
        return BeamMesh.hermite(m.points, tangents, elements)
    return BeamMesh.lagrange(m.points, elements)


def build_beam_mesh(spec, path):
    """BeamMesh of one validated ``beams[i]`` entry (``hermite`` for torsion_free, ``line`` for truss)."""
    hermite = spec["model"] == "torsion_free"
    try:
        if "mesh" in spec:
            mesh = spec["mesh"]
            if isinstance(mesh, BeamMesh):
                check_beam_nodes(mesh, f"{path}.mesh")
                return mesh
            beams = _read_beam_file(mesh, hermite, f"{path}.mesh")
            check_beam_nodes(beams, f"{path}.mesh {str(mesh)!r}")
            return beams
        curve, n = spec["curve"], spec["elements"]
        if "polyline" in curve:
            pts = curve["polyline"]
            elements = np.column_stack([np.arange(n), np.arange(1, n + 1)])
            return BeamMesh.hermite(pts, _chord_tangents(pts), elements) if hermite else BeamMesh.lagrange(pts, elements)
        f, df, t0, t1 = _curve_functions(curve)
        if hermite:
            return BeamMesh.from_curve(f, df, t0, t1, n)
        t = np.linspace(t0, t1, n + 1)
        pts = np.array([np.asarray(f(ti), dtype=float).reshape(3) for ti in t])
        return BeamMesh.lagrange(pts, np.column_stack([np.arange(n), np.arange(1, n + 1)]))
    except MeshError as exc:
        raise SceneError(f"{path}: {exc}") from None


def check_straight_torsion_free(mesh, path):
    """SceneError naming ``path`` if a torsion_free beam's reference centreline is curved.

    The torsion-free theory holds for initially straight beams only (see
    :class:`~mortar1d3d.physics.beam.BeamModel`); curved is decided by
    :func:`~mortar1d3d.physics.beam.curved_elements` (curvature times element length above 1e-8).
    """
    from .physics.beam import curved_elements, curved_torsion_free_message
    ids, values = curved_elements(mesh)
    if ids.size:
        raise SceneError(f"{path}.model: {curved_torsion_free_message(ids, values, mesh.n_elements)}")


def build_solid_mesh(spec):
    mesh = spec["mesh"]
    try:
        if isinstance(mesh, dict):
            return box_mesh(mesh["box"][0], mesh["box"][1], mesh["cells"], mesh["element"])
        if not isinstance(mesh, SolidMesh):
            mesh = SolidMesh.from_meshio(read_mesh_file(mesh, "solid.mesh"))
    except (MeshError, OSError) as exc:
        raise SceneError(f"solid.mesh: {exc}") from None
    check_solid_nodes(mesh, "solid.mesh")
    return mesh


def free_rigid_motions(R, Rf, tol, centre, size):
    """Names of a basis of the rigid-body motions of a body that its supports do not stop.

    Parameters
    ----------
    R : (m, 6) float
        The body's rigid-body modes (:meth:`Model.rigid_body_modes` restricted to its DOFs):
        translations in x, y, z, then rotations about x, y, z through ``centre`` with the
        positions scaled by ``1/size``.
    Rf : (k, 6) float
        The rows of ``R`` at fixed DOFs.
    tol : float
        Singular values up to ``tol`` count as zero (the rank threshold of the caller).
    centre : (3,) float
    size : float

    Returns
    -------
    list of str
        One name per free motion, ``rank(R) − rank(Rf)`` of them: the free motions are ``R a``
        with ``Rf a = 0``, counted modulo the coefficients ``a`` that move nothing (``R a = 0``,
        e.g. a straight torsion-free beam turning about its own axis). The basis is the reduced
        row echelon form with rotations first: a single-axis motion gets its plain name ("rotation
        about x"), any other an axis direction and, when it does not pass through the centroid,
        a point on it.
    """
    _, s, Vt = np.linalg.svd(R)
    row = Vt[: np.count_nonzero(s > tol)]                   # coefficients that move the body
    if len(Rf):
        _, sf, Vft = np.linalg.svd(Rf)
        null = Vft[np.count_nonzero(sf > tol):]             # coefficients the supports do not see
    else:
        null = np.eye(6)
    # null(Rf) is the orthogonal sum of null(R) and null(Rf) ∩ row(R): projecting it onto row(R)
    # leaves the free motions, with singular values 1 (kept) or 0 (motions that move nothing)
    _, sp_, basis = np.linalg.svd(null @ row.T @ row)
    basis = basis[: np.count_nonzero(sp_ > 0.5)]
    order = [3, 4, 5, 0, 1, 2]                              # rotations first: pivots on rotations
    A = basis[:, order]
    r = 0
    for c in range(6):
        if r == len(A):
            break
        p = r + int(np.argmax(np.abs(A[r:, c])))
        if abs(A[p, c]) <= 1e-8:                             # rows are orthonormal: O(1) entries
            continue
        A[[r, p]] = A[[p, r]]
        A[r] /= A[r, c]
        others = np.arange(len(A)) != r
        A[others] -= np.outer(A[others, c], A[r])
        r += 1
    coefficients = np.empty_like(A)
    coefficients[:, order] = A
    names = [_motion_name(a[:3], a[3:] / size, centre, size) for a in coefficients]
    return sorted(names, key=lambda name: not name.startswith("translation"))


def _motion_name(v, w, centre, size):
    """Name of the rigid motion ``u(X) = v + w × (X − centre)``."""
    def direction(d):
        d = d / np.linalg.norm(d)
        d = np.where(np.abs(d) <= 1e-9, 0.0, d)
        d = d if d[np.flatnonzero(d)[0]] > 0 else -d            # a motion's sign is arbitrary
        nonzero = np.flatnonzero(d)
        if len(nonzero) == 1:
            return "xyz"[nonzero[0]]
        return "(" + ", ".join(f"{x:.3g}" for x in d + 0.0) + ")"

    wn, vn = float(np.linalg.norm(w)), float(np.linalg.norm(v))
    if wn * size <= 1e-9 * vn:
        d = direction(v)
        return f"translation {'in' if len(d) == 1 else 'along'} {d}"
    axis = w / wn
    name = f"rotation about {direction(w)}"
    offset = np.cross(w, v) / wn ** 2                          # centroid → nearest point of the axis
    if np.linalg.norm(offset) > 1e-9 * size:
        point = centre + offset
        # round-off of the coordinates (scale: size and distance from the origin) printed as 0
        point[np.abs(point) <= 1e-9 * (size + np.abs(centre).max())] = 0.0
        name += " through (" + ", ".join(f"{x:.4g}" for x in point + 0.0) + ")"
    slide = float(v @ axis) / wn                                # translation along the axis per radian
    if abs(slide) > 1e-9 * size:
        name += f" with a slide of {slide:.3g} along it per radian (screw)"
    return name


@dataclass
class BeamGroup:
    """Beams of one model in one BeamMesh (entries keep their order)."""

    model: str
    entries: list                      # scene beam indices
    mesh: BeamMesh = None
    node_offsets: list = field(default_factory=list)     # first node of each entry in ``mesh``
    element_offsets: list = field(default_factory=list)
    entry_elements: list = field(default_factory=list)   # (start, stop) element range per entry
    dof_offset: int = 0
    physics: object = None             # BeamModel
    operators: object = None           # MortarOperators
    coupling: object = None            # Coupling

    @property
    def dofs_per_node(self):
        return 6 if self.model == "torsion_free" else 3


class Model:
    """Meshes, sets, and (after :meth:`prepare`) the operators of a scene.

    Construction is cheap (meshes and sets only); :meth:`prepare` assembles what the scene
    needs. ``counts`` records every stage that ran.
    """

    def __init__(self, scene):
        if not isinstance(scene, Scene):
            raise TypeError(f"expected a Scene, got {type(scene).__name__}")
        self.scene = scene
        self.counts = Counter()
        self.linear = scene.analysis["kinematics"] == "linear"
        self.solid_mesh = build_solid_mesh(scene.solid) if scene.solid is not None else None
        self.n_solid_nodes = self.solid_mesh.n_nodes if self.solid_mesh is not None else 0
        # beams grouped by model, entry order kept inside each group
        self.groups, self.entry_group = [], []
        meshes = [build_beam_mesh(b, f"beams[{i}]") for i, b in enumerate(scene.beams)]
        for i, (b, mesh) in enumerate(zip(scene.beams, meshes)):
            if b["model"] == "torsion_free":
                check_straight_torsion_free(mesh, f"beams[{i}]")
        for i, b in enumerate(scene.beams):
            group = next((g for g in self.groups if g.model == b["model"]), None)
            if group is None:
                group = BeamGroup(model=b["model"], entries=[])
                self.groups.append(group)
            group.entries.append(i)
            self.entry_group.append(group)
        offset = 3 * self.n_solid_nodes
        for g in self.groups:
            parts = [meshes[i] for i in g.entries]
            g.mesh = parts[0] if len(parts) == 1 else BeamMesh.join(parts)
            g.node_offsets = list(np.cumsum([0] + [p.n_nodes for p in parts[:-1]]))
            g.element_offsets = list(np.cumsum([0] + [p.n_elements for p in parts[:-1]]))
            g.entry_elements = [(int(o), int(o) + p.n_elements) for o, p in zip(g.element_offsets, parts)]
            g.dof_offset = offset
            offset += g.mesh.n_centreline_dofs
        self.n_displacement_dofs = offset
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
        self.fibre_regions = self._fibre_regions()
        self.prepared = False
        self._follow = None          # auxiliary-space split, built on first use (_follow_split)

    # -- sets -----------------------------------------------------------------------------------
    def _beam_nodes(self, entry, which, path):
        if entry >= len(self.scene.beams):
            n = len(self.scene.beams)
            raise SceneError(f"{path}: beam {entry} does not exist (the scene has {n} beam{'s' if n != 1 else ''})")
        g = self.entry_group[entry]
        k = g.entries.index(entry)
        start, stop = g.entry_elements[k]
        if which == "start":
            return g, g.mesh.elements[start, :1].copy()
        if which == "end":
            return g, g.mesh.elements[stop - 1, 1:2].copy()
        return g, np.unique(g.mesh.elements[start:stop])

    def select(self, spec, path):
        """Resolve a set spec to ``("solid", node ids)`` or ``("beam", group, node ids)``.

        Raises SceneError (naming ``path``) when the set selects nothing.
        """
        if isinstance(spec, dict):
            if self.solid_mesh is None:
                raise SceneError(f"{path}: 'inside' selects solid nodes, but the scene has no solid")
            lo, hi = np.asarray(spec["inside"], dtype=float)
            X = self.solid_mesh.points
            tol = 1e-9 * float(np.linalg.norm(np.ptp(X, axis=0)))
            nodes = np.flatnonzero(((X >= lo - tol) & (X <= hi + tol)).all(axis=1))
            if nodes.size == 0:
                raise SceneError(f"{path}: the box {lo.tolist()} – {hi.tolist()} contains no solid node")
            return ("solid", nodes)
        parts = spec.split(":")
        if parts[0] == "solid":
            if self.solid_mesh is None:
                raise SceneError(f"{path}: {spec!r} names a solid set, but the scene has no solid")
            name = parts[1]
            X = self.solid_mesh.points
            if name in BOX_FACES:
                axis = "xyz".index(name[0])
                target = X[:, axis].min() if name.endswith("min") else X[:, axis].max()
                tol = 1e-9 * float(np.linalg.norm(np.ptp(X, axis=0)))
                nodes = np.flatnonzero(np.abs(X[:, axis] - target) <= tol)
            elif name in self.solid_mesh.point_sets:
                nodes = np.unique(np.asarray(self.solid_mesh.point_sets[name], dtype=np.int64))
            else:
                known = sorted(set(BOX_FACES) | set(self.solid_mesh.point_sets))
                raise SceneError(f"{path}: unknown solid set {name!r}; known: {', '.join(known)}")
            if nodes.size == 0:
                raise SceneError(f"{path}: {spec!r} selects no node")
            return ("solid", nodes)
        entry = int(parts[1])
        g, nodes = self._beam_nodes(entry, parts[2] if len(parts) == 3 else None, path)
        return ("beam", g, nodes)

    def _set_dofs(self, sel, components, tangents=False):
        comps = np.asarray(components, dtype=np.int64)
        if sel[0] == "solid":
            return (3 * sel[1][:, None] + comps[None, :]).ravel()
        g, nodes = sel[1], sel[2]
        base = g.dof_offset + g.dofs_per_node * nodes[:, None] + (3 if tangents else 0)
        return (base + comps[None, :]).ravel()

    def _dirichlet(self):
        """Fixed DOFs and their values in the basis of the unknowns, the position DOFs of each entry
        (for its reaction), and that basis (:class:`~mortar1d3d.supports.RotatedBasis` of the clamps)."""
        dofs, values, per_entry = [], [], []
        clamps = {}
        for i, d in enumerate(self.scene.dirichlet):
            sel = self.select(d["on"], f"dirichlet[{i}].on")
            idx = self._set_dofs(sel, d["components"])
            val = np.tile(d["value"][d["components"]], len(idx) // len(d["components"]))
            dofs.append(idx)
            values.append(val)
            if d["clamp"]:
                g = sel[1]
                if g.model != "torsion_free":
                    raise SceneError(f"dirichlet[{i}].clamp: beam {d['on']!r} has no tangent DOFs ({g.model})")
                starts, frames = self._clamp_frames(g, sel[2])
                clamps.update(zip(starts.tolist(), frames))
                t_idx = (starts[:, None] + np.arange(2)).ravel()      # e1·Δt, e2·Δt in the rotated frame
                dofs.append(t_idx)
                values.append(np.zeros(len(t_idx)))
            per_entry.append(idx)     # position DOFs only: their reactions are forces
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

    @staticmethod
    def _clamp_frames(g, nodes):
        """First tangent DOF of each clamped node and its frame ``(e1, e2, t0)``.

        At a Hermite node the tangent's length is the local stretch: a clamp fixes only its
        direction, the components along ``e1`` and ``e2`` (see :mod:`mortar1d3d.supports`), so
        that a clamped beam behaves the same in every orientation.
        """
        starts = g.dof_offset + 6 * np.asarray(nodes, dtype=np.int64) + 3
        return starts, [clamp_frame(g.mesh.tangents[node]) for node in nodes]

    def _check_solver(self):
        solver, enforcement = self.scene.analysis["solver"], self.scene.coupling["enforcement"]
        lagrange = self.scene.coupled and enforcement == "lagrange"
        if solver == "block" and not lagrange:
            raise SceneError("analysis.solver: 'block' is the saddle-point solver of Lagrange-multiplier coupling; "
                             "use 'auto', 'direct' or 'amg'")
        if solver == "amg" and lagrange:
            raise SceneError("analysis.solver: Lagrange-multiplier coupling gives a saddle point; use 'auto', "
                             "'direct' or 'block' (MINRES, the auxiliary-space AMG inside a block preconditioner)")

    # -- effects --------------------------------------------------------------------------------
    @property
    def lagrange(self):
        return self.scene.coupled and self.scene.coupling["enforcement"] == "lagrange"

    def linear_solver_method(self, n_unknowns=None):
        """The linear solver that ``analysis.solver`` resolves to for this model."""
        solver = self.scene.analysis["solver"]
        if solver != "auto":
            return solver
        from .solvers.direct import DIRECT_MAX_DOFS
        n = self.n_displacement_dofs if n_unknowns is None else n_unknowns
        if n <= DIRECT_MAX_DOFS:
            return "direct"
        return "block" if self.lagrange else "amg"

    def effects(self):
        """The list of :class:`Effect` that :func:`solve` will run for this scene."""
        sc, nonlinear = self.scene, not self.linear
        every = "every iteration" if nonlinear else "once"
        out = []
        if self.solid_mesh is not None:
            m = self.solid_mesh
            kinds = ", ".join(f"{len(c)} {d.name}" for d, c in m.blocks)
            out.append(Effect("solid.mesh", "once", f"{kinds}; {m.n_nodes} nodes"))
        for g in self.groups:
            out.append(Effect("beams.mesh", "once", f"{g.model}: {len(g.entries)} beam(s), {g.mesh.n_elements} "
                                                    f"{g.mesh.element_type.name} elements"))
        if sc.coupled:
            c = sc.coupling
            out.append(Effect("mortar.search", "once", "broad phase, reference configuration"))
            if c["integration"] == "segment":
                out.append(Effect("mortar.segmentation", "once", f"beam–face intersections, {c['search_points']} "
                                                                 "search points"))
            elif c["integration"] == "auto":
                out.append(Effect("mortar.segmentation", "once", "only beam elements that cross element faces "
                                                                 f"({c['search_points']} search points)"))
            out.append(Effect("mortar.integration_points", "once", f"{c['integration']}-based, n_gauss={c['n_gauss']}"))
            out.append(Effect("mortar.assembly", "once", f"D, M, kappa (lm={c['lm']})"))
            if c["enforcement"] == "lagrange":
                out.append(Effect("coupling.lagrange", "once", f"constraint rows B = [-M, D] ({c['constraint']})"))
            else:
                out.append(Effect(f"coupling.{c['constraint']}_penalty", "once",
                                  f"constant stiffness, penalty {self.penalty:.4g}"))
        out.append(Effect("check.rigid_body_modes", "once", "before any solve"))
        if self.groups:
            out.append(Effect("check.zero_energy_modes", "once", "beam mechanisms, before any solve"))
        if self.solid_mesh is not None:
            mat = sc.solid["material"]["model"]
            if sc.solid["material"].get("fibres"):
                mat += f" + {len(sc.solid['material']['fibres'])} fibre families"
            if nonlinear:
                out.append(Effect("solid.internal_force", every, f"total Lagrangian, {mat}"))
                out.append(Effect("solid.tangent", every, "consistent tangent"))
            else:
                out.append(Effect("solid.stiffness", "once", f"small strain, {mat}"))
        if self.groups:
            if nonlinear:
                out.append(Effect("beam.internal_force", every, ", ".join(g.model for g in self.groups)))
                out.append(Effect("beam.tangent", every, "consistent tangent"))
            else:
                out.append(Effect("beam.stiffness", "once", "linearised at the reference configuration"))
        kinds = {item["type"] for item in sc.loads}
        for kind, when, detail in (("point", "once", "dead nodal forces"),
                                   ("traction", "once", "dead surface traction"),
                                   ("body", "once", "dead body force")):
            if kind in kinds:
                out.append(Effect(f"load.{kind}", when, detail))
        if "pressure" in kinds:
            if nonlinear:
                out.append(Effect("load.pressure", every, "follower pressure on the current surface"))
                out.append(Effect("load.pressure_tangent", every, "load stiffness of the follower pressure"))
            else:
                out.append(Effect("load.pressure", "once", "pressure on the reference surface (linear kinematics)"))
        if "moment" in kinds:
            out.append(Effect("load.moment", every, "beam end moment"))
        if nonlinear:
            a = sc.analysis
            out.append(Effect("solver.newton", "every load step", f"{a['steps']} load steps, rtol {a['rtol']:g}, "
                                                                  f"at most {a['max_iterations']} iterations"))
        else:
            out.append(Effect("solver.linear", "once", "one linear solve, no Newton loop"))
        method = self.linear_solver_method()
        amg = ("CG + auxiliary-space preconditioner (AMG on the solid carrying its beams, beam blocks "
               "factorised)" if self._auxiliary_space() else "CG + smoothed aggregation AMG (rigid-body modes)")
        detail = {"direct": "sparse LU (scipy)", "amg": amg,
                  "block": "MINRES + block preconditioner (auxiliary space on the augmented stiffness, Schur "
                           "from kappa)"}[method]
        out.append(Effect(f"linear_solver.{method}", every, detail))
        if (method == "amg" and self._auxiliary_space()) or (method == "block" and self._auxiliary_space(True)):
            out.append(Effect("linear_solver.follow_operator", "once", "beam DOFs following the solid "
                                                                        "(prolongation of the auxiliary space)"))
        return out

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
        from .physics.beam import BeamModel
        from .physics.coupling import Coupling
        from .physics.materials import material
        from .physics.solid import SolidModel
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
            EA = np.concatenate([np.full(b - a, sc.beams[i]["section"]["EA"]) for i, (a, b) in zip(g.entries, g.entry_elements)])
            EI = np.concatenate([np.full(b - a, sc.beams[i]["section"]["EI"]) for i, (a, b) in zip(g.entries, g.entry_elements)])
            g.physics = BeamModel(g.mesh, EA, EI, model=g.model)
        if sc.coupled:
            c = sc.coupling
            for k, g in enumerate(self.groups):
                if operators is not None:
                    g.operators = operators[k]
                else:
                    g.operators = assemble_mortar(g.mesh, self.solid_mesh, integration=c["integration"],
                                                  n_gauss=c["n_gauss"], lm=c["lm"], search_points=c["search_points"])
                    self.counts["mortar.search"] += 1
                    if c["integration"] in ("segment", "auto"):
                        self.counts["mortar.segmentation"] += 1
                    self.counts["mortar.integration_points"] += 1
                    self.counts["mortar.assembly"] += 1
                g.coupling = Coupling(g.operators, g.mesh, self.solid_mesh, g.dof_offset, n,
                                      constraint=c["constraint"], enforcement=c["enforcement"], penalty=self.penalty)
                self.counts["coupling.lagrange" if self.lagrange else f"coupling.{c['constraint']}_penalty"] += 1
                coupled = np.unique(g.operators.point_fields["beam_element"])
                for entry, (a, b) in zip(g.entries, g.entry_elements):
                    if not np.any((coupled >= a) & (coupled < b)):
                        warnings.warn(f"beams[{entry}]: no part of this beam lies inside the solid, so it is not "
                                      "coupled (check the units: a mm/m mix-up moves a beam out of the solid)",
                                      CouplingWarning, stacklevel=3)
            if self.lagrange:
                self.constraint_matrix = sp.vstack([g.coupling.constraint_matrix() for g in self.groups], format="csr")
                self.n_multipliers = self.constraint_matrix.shape[0]
            else:
                K = self.groups[0].coupling.K
                for g in self.groups[1:]:
                    K = K + g.coupling.K
                self.coupling_stiffness = K.tocsr()
        self._prepare_loads()
        self.n_unknowns = n + self.n_multipliers
        self.free = np.setdiff1d(np.arange(self.n_unknowns), self.fixed_dofs)
        self.fixed = self.fixed_dofs
        self.check_supports()
        self.prepared = True
        return self

    def _check_operators(self, operators):
        """Validate precomputed operators against the groups' meshes and the scene's LM type."""
        if not self.scene.coupled:
            raise ValueError("prepare(operators=...): the scene has no coupling (it needs a solid and beams)")
        operators = list(operators)
        if len(operators) != len(self.groups):
            raise ValueError(f"prepare(operators=...): expected {len(self.groups)} operator set(s), one per beam "
                             f"group ({', '.join(g.model for g in self.groups)}), got {len(operators)}")
        from .elements.multiplier import multiplier
        from .mortar.assemble import lm_numbering
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

    def _fibre_regions(self):
        """Per ``solid.material.fibres`` family: None (every element) or the mask of the elements
        whose node centroid lies in its ``inside`` box."""
        families = self.scene.solid["material"].get("fibres", ()) if self.solid_mesh is not None else ()
        mesh = self.solid_mesh
        out = []
        for i, f in enumerate(families):
            elements = None
            if f["inside"] is not None:
                lo, hi = f["inside"]
                conn = mesh.connectivity
                valid = conn >= 0
                centroid = (mesh.points[np.where(valid, conn, 0)] * valid[..., None]).sum(axis=1) / valid.sum(axis=1)[:, None]
                tol = 1e-9 * float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
                elements = ((centroid >= lo - tol) & (centroid <= hi + tol)).all(axis=1)
                if not elements.any():
                    raise SceneError(f"solid.material.fibres[{i}].inside: no element centroid lies in "
                                     f"{lo.tolist()} – {hi.tolist()}")
            out.append(elements)
        return out

    def _fibre_field(self, families):
        """FibreField of ``solid.material.fibres``: a family without ``inside`` reinforces every
        element, one with ``inside`` the elements of its region (:meth:`_fibre_regions`)."""
        from .physics.fibre_material import FibreField, fibre_family
        rows = []
        for i, (f, elements) in enumerate(zip(families, self.fibre_regions)):
            row = fibre_family(f["direction"], f["E"], f["volume_fraction"], f"solid.material.fibres[{i}]")
            rows.append((row, elements))
        return FibreField(self.solid_mesh.n_elements, rows)

    def _load_sets(self):
        """Per ``load`` entry: its resolved set (None for a body force) and, for surface loads,
        its boundary faces."""
        from .physics.surface import boundary_faces
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
        from .physics.surface import Pressure, traction_force
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
            else:   # moment on a Hermite beam end: acts on the node's tangent DOFs
                g, nodes = sel[1], sel[2]
                dofs = g.dof_offset + 6 * nodes[0] + 3 + np.arange(3)
                self.moments.append((dofs, item["value"]))
        if self.linear:
            # linear kinematics: pressure and moments are evaluated once, on the reference configuration
            for p in self.pressures:
                f, _ = p.evaluate(np.zeros(3 * self.n_solid_nodes), tangent=False)
                self.dead_load[: 3 * self.n_solid_nodes] += f
                self.counts["load.pressure"] += 1
            for dofs, moment in self.moments:
                from .physics.beam import end_moment
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
                ref[g.dof_offset: g.dof_offset + g.mesh.n_centreline_dofs] = g.mesh.centreline_dofs()
            self._reference = ref
        return self._reference

    # -- supports -------------------------------------------------------------------------------
    def _bodies(self):
        """Groups of displacement DOFs that move together (solid + coupled beams; free beams alone)."""
        bodies = []
        solid_body = [np.arange(3 * self.n_solid_nodes)] if self.solid_mesh is not None else []
        for g in self.groups:
            coupled_elements = (np.unique(g.operators.point_fields["beam_element"]) if g.operators is not None
                                else np.zeros(0, np.int64))
            for k, entry in enumerate(g.entries):
                a, b = g.entry_elements[k]
                nodes = np.unique(g.mesh.elements[a:b])
                dofs = (g.dof_offset + g.dofs_per_node * nodes[:, None] + np.arange(g.dofs_per_node)).ravel()
                inside = np.any((coupled_elements >= a) & (coupled_elements < b))
                if inside:
                    solid_body.append(dofs)
                else:
                    bodies.append((f"beam {entry}" + (" (outside the solid, so not coupled)"
                                                      if self.solid_mesh is not None else ""), dofs))
        if solid_body:
            label = "the solid" + (" with its coupled beams" if len(solid_body) > 1 else "")
            bodies.insert(0, (label, np.concatenate(solid_body)))
        return bodies

    def _tangent_triplets(self):
        """(n_displacement_dofs // 3,) bool: which DOF triplets are Hermite tangents."""
        is_tangent = np.zeros(self.n_displacement_dofs // 3, dtype=bool)
        for g in self.groups:
            if g.model == "torsion_free":
                first = g.dof_offset // 3
                is_tangent[first + 1: first + 2 * g.mesh.n_nodes: 2] = True
        return is_tangent

    def _mode_frame(self, dofs, is_tangent):
        """Centre and length scale of :meth:`rigid_body_modes`: the centroid and the largest extent
        of the positions among ``dofs`` (all when None)."""
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
        from .solvers.rigid import rigid_body_modes
        is_tangent = self._tangent_triplets()
        centre, size = self._mode_frame(dofs, is_tangent)
        R = rigid_body_modes(self.reference().reshape(-1, 3), is_tangent, centre=centre, scale=size)
        return self.basis.to_unknowns(R)

    def check_supports(self):
        """Raise SceneError if a body can move as a rigid body (before any solve)."""
        self.counts["check.rigid_body_modes"] += 1
        fixed = np.zeros(self.n_displacement_dofs, dtype=bool)
        fixed[self.fixed_dofs[self.fixed_dofs < self.n_displacement_dofs]] = True
        for label, dofs in self._bodies():
            R = self.rigid_body_modes(dofs)[dofs]
            s_all = np.linalg.svd(R, compute_uv=False)
            rank_all = int(np.count_nonzero(s_all > 1e-10 * s_all[0]))
            Rf = R[fixed[dofs]]
            if len(Rf):
                s_fix = np.linalg.svd(Rf, compute_uv=False)
                rank_fix = int(np.count_nonzero(s_fix > 1e-10 * s_all[0]))
            else:
                rank_fix = 0
            if rank_fix < rank_all:
                centre, size = self._mode_frame(dofs, self._tangent_triplets())
                free = free_rigid_motions(R, Rf, 1e-10 * s_all[0], centre, size)
                raise SceneError(f"dirichlet: {label} can move freely ({len(free)} rigid-body mode(s) not "
                                 f"fixed: {', '.join(free)}); add supports ([[dirichlet]]) that stop these motions")
        self.check_zero_energy_modes()

    def check_linear_displacements(self, z):
        """Warn (LargeDeformationWarning) for each body that the linear solution ``z`` (unknowns)
        moves by more than LINEAR_DISPLACEMENT_LIMIT of its size, the diagonal of its bounding box:
        linear kinematics assumes displacements small against the body."""
        u = self.basis.to_physical(z[: self.n_displacement_dofs]).reshape(-1, 3)
        X = self.reference().reshape(-1, 3)
        position = ~self._tangent_triplets()
        for label, dofs in self._bodies():
            triplets = np.unique(dofs // 3)
            triplets = triplets[position[triplets]]
            size = float(np.linalg.norm(np.ptp(X[triplets], axis=0)))
            umax = float(np.linalg.norm(u[triplets], axis=1).max())
            if umax > LINEAR_DISPLACEMENT_LIMIT * size:
                warnings.warn(f"analysis.kinematics: {label} moves by up to {umax:.3g}, {umax / size:.3g} times its "
                              f"size {size:.3g} (the diagonal of its bounding box); with displacements that large, "
                              "linear kinematics does not hold. Check the units (E in Pa, not MPa, for a scene in "
                              "metres and newtons) or use kinematics = \"nonlinear\"", LargeDeformationWarning,
                              stacklevel=3)

    def check_zero_energy_modes(self):
        """Raise SceneError if a beam has a zero-energy mode other than a rigid-body motion.

        Runs after the rigid-body check (so every body is held against rigid motion): each chain
        of beam elements is probed with the solid held, on its free DOFs, for motions that
        neither the beam stiffness at the reference state nor the coupling resists
        (:func:`~mortar1d3d.mechanisms.find_mechanisms`). The modes found are kept in
        ``zero_energy_modes`` (list of ``(group, Mechanism)``) before the error is raised.
        """
        from .mechanisms import chains, find_mechanisms
        self.zero_energy_modes = []
        if not self.groups:
            return
        self.counts["check.zero_energy_modes"] += 1
        fixed = np.zeros(self.n_displacement_dofs, dtype=bool)
        fixed[self.fixed_dofs[self.fixed_dofs < self.n_displacement_dofs]] = True
        # a clamped tangent is fixed in its rotated frame (direction, not length): the probe works on
        # physical components and holds the whole tangent there, which hides no mechanism (changing the
        # tangent's length alone stretches the element)
        for first in self.basis.starts:
            fixed[first: first + 3] = fixed[first: first + 3].any()
        for g in self.groups:
            rows = None
            if g.operators is not None:
                if self.scene.coupling["constraint"] == "gauss_point":
                    rows = g.coupling.G[:, g.dof_offset: g.dof_offset + g.mesh.n_centreline_dofs]
                else:
                    rows = g.operators.D.tocsr()[g.coupling.coupled_rows]
            sl = slice(g.dof_offset, g.dof_offset + g.mesh.n_centreline_dofs)
            found = find_mechanisms(g.mesh, rows, fixed[sl])
            self.zero_energy_modes += [(g, m) for m in found]
        if self.zero_energy_modes:
            g, m = self.zero_energy_modes[0]
            more = len(self.zero_energy_modes) - 1
            raise SceneError(self._mechanism_message(g, m, chains(g.mesh)[1])
                             + (f" ({more} more chain(s) of beam elements have such modes)" if more else ""))

    def _mechanism_message(self, g, m, label):
        """The SceneError text of one zero-energy mode: which beam, which nodes, why, what to do."""
        k = int(np.searchsorted(g.node_offsets, m.nodes[0], side="right")) - 1
        entry, first = g.entries[k], int(g.node_offsets[k])
        last = int(g.node_offsets[k + 1]) if k + 1 < len(g.node_offsets) else g.mesh.n_nodes
        entry_chains = np.unique(label[first:last])
        where = f"beams[{entry}]"
        if len(entry_chains) > 1:
            where += (f" (chain {int(np.searchsorted(entry_chains, m.chain))} of its {len(entry_chains)} "
                      f"unconnected chains, nodes {m.nodes[0] - first}..{m.nodes[-1] - first})")
        local = m.moving - first
        per_node = 6 if g.model == "torsion_free" else 3
        node = int(m.moving[0])
        comps = np.abs(m.mode[per_node * node: per_node * node + 3])
        axis = "xyz"[int(np.argmax(comps))] if comps.max() > 0 else "its tangent"
        coupled = np.zeros(g.mesh.n_nodes, dtype=bool)
        if g.operators is not None:
            elements = np.unique(g.operators.point_fields["beam_element"])
            coupled[np.unique(g.mesh.elements[elements])] = True
        outside = ~coupled[m.moving]
        if outside.all() and self.solid_mesh is None:
            why = "nothing but the beam itself holds the moving nodes"
            advice = ("a truss has no bending stiffness, so between supports its nodes are held only along its bars: "
                      "support them sideways ([[dirichlet]] with components) or use model = \"torsion_free\" "
                      "(straight beams)" if g.model == "truss" else "support the moving nodes ([[dirichlet]])")
        elif outside.all():
            why = "the moving nodes are not coupled to the solid (they lie outside it)"
            advice = ("a truss has no bending stiffness, so an uncoupled part of it is held only along its bars: "
                      "support these nodes ([[dirichlet]]), end the beam where it leaves the solid, or use "
                      "model = \"torsion_free\" (straight beams)" if g.model == "truss" else
                      "support the moving nodes ([[dirichlet]])")
        else:
            why = "the coupling holds this beam at too few places"
            advice = ("couple more of it: integration = \"segment\" or more Gauss points (n_gauss) where a beam "
                      "element barely enters the solid, or support it ([[dirichlet]])")
        return (f"{where}: zero-energy mode (a mechanism: the beam can move without any stiffness against it, so "
                f"no solver can determine that motion): "
                + (f"nodes {format_ids(local)} move (largest: node {local[0]}, " if len(local) > 1 else
                   f"node {local[0]} moves (")
                + f"{axis}); {why}. {advice[0].upper() + advice[1:]}")

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

    def internal(self, d, tangent=True):
        """Internal forces and tangent of solid + beams + penalty coupling at displacements ``d``."""
        n = self.n_displacement_dofs
        r = np.zeros(n)
        blocks = []
        if self.solid_mesh is not None:
            nS = 3 * self.n_solid_nodes
            f, K = self.solid_physics.evaluate(d[:nS], tangent=tangent)
            self._count("solid", tangent)
            r[:nS] = f
            blocks.append(K)
        for g in self.groups:
            sl = slice(g.dof_offset, g.dof_offset + g.mesh.n_centreline_dofs)
            f, K = g.physics.evaluate(d[sl], tangent=tangent)
            self._count("beam", tangent)
            r[sl] = f
            blocks.append(K)
        K = sp.block_diag(blocks, format="csr") if tangent else None
        if self.scene.coupled and not self.lagrange:
            r += self.coupling_stiffness @ d
            if tangent:
                K = K + self.coupling_stiffness
        return r, K

    def residual(self, z, t, tangent=True):
        """Residual ``r = f_int + (coupling) − t f_ext`` over all unknowns, and its Jacobian.

        ``z``, ``r`` and the Jacobian are in the basis of the unknowns (``self.basis``: clamped
        tangents in their rotated frames); the physics is evaluated on physical components.
        """
        n = self.n_displacement_dofs
        d = self.basis.to_physical(z[:n])
        r, K = self.internal(d, tangent)
        r -= t * self.dead_load
        nS = 3 * self.n_solid_nodes
        for p in self.pressures:
            f, Kp = p.evaluate(d[:nS], tangent=tangent)
            self.counts["load.pressure"] += 1
            r[:nS] -= t * f
            if tangent:
                self.counts["load.pressure_tangent"] += 1
                K = K - t * self._embed(Kp, 0)
        if self.moments:
            from .physics.beam import end_moment
            q = self.reference() + d
            for dofs, moment in self.moments:
                f, Km = end_moment(q[dofs], t * moment)
                self.counts["load.moment"] += 1
                r[dofs] -= f
                if tangent:
                    K = K - sp.csr_matrix((Km.ravel(), (np.repeat(dofs, 3), np.tile(dofs, 3))), shape=K.shape)
        if self.lagrange:
            B, lam = self.constraint_matrix, z[n:]
            r = np.concatenate([r + B.T @ lam, B @ d])
            if tangent:
                K = sp.bmat([[K, B.T], [B, None]], format="csr")
        r, K = self.basis.to_unknowns(r), self.basis.matrix(K)
        self.last_residual = r
        return r, (K.tocsr() if tangent else None)

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
            from .physics.coupling import follow_operator
            nS = 3 * self.n_solid_nodes
            free = self.free[self.free < self.n_displacement_dofs]
            blocks = [follow_operator(g.operators, g.mesh) for g in self.groups]
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
            from .elements.multiplier import multiplier
            from .mortar.assemble import lm_numbering
            from .solvers.linear import DEPENDENT_ROW_TOLERANCE, dependent_rows
            dep = dependent_rows(B, beam)
            if len(dep):
                # each row of B: (beam entry, LM node as a row of Result.line_load, component)
                entry, lm_node, comp, first = [], [], [], 0
                for g in self.groups:
                    index, n_lm = lm_numbering(g.mesh, multiplier(self.scene.coupling["lm"]))
                    owner = np.zeros(n_lm, dtype=np.int64)
                    for k, (start, stop) in enumerate(g.entry_elements):
                        owner[index[start:stop][index[start:stop] >= 0]] = g.entries[k]
                    rows = g.coupling.coupled_rows
                    entry.append(owner[rows // 3])
                    lm_node.append(first + rows // 3)
                    comp.append(rows % 3)
                    first += n_lm
                entry, lm_node, comp = (np.concatenate(v)[dep.rows] for v in (entry, lm_node, comp))
                parts = []
                for e in np.unique(entry):
                    nodes = [f"{j} ({', '.join('xyz'[c] for c in comp[(entry == e) & (lm_node == j)])})"
                             for j in np.unique(lm_node[entry == e])]
                    parts.append(f"beams[{e}] LM nodes {', '.join(nodes)}")
                what = "; ".join(parts)
                # prescribed values must satisfy the dropped rows through the kept ones
                # (fixed DOFs and values are in the unknowns' basis: clamped tangents in rotated frames)
                Bu = self.constraint_matrix @ self.basis.matrix_T(self.n_displacement_dofs) if self.basis \
                    else self.constraint_matrix
                Bf, v, C = Bu.tocsc()[:, self.fixed_dofs], self.fixed_values, dep.combinations
                gap = np.abs(C @ (Bf @ v))
                size = abs(C) @ (abs(Bf) @ np.abs(v))
                if np.any(gap > DEPENDENT_ROW_TOLERANCE * size):
                    raise SceneError(f"dirichlet: the prescribed values contradict the coupling: the rows of {what} "
                                     "are combinations of other coupling rows, and the prescribed displacements "
                                     "satisfy those but not these (prescribe values the embedded beams can follow)")
                warnings.warn(f"coupling.lm: the coupling rows of {what} are combinations of the other rows (the "
                              f"multipliers, lm = {self.scene.coupling['lm']!r}, are richer than what the solid mesh "
                              "resolves along the beam, or supports fixed what they act on); they are left out, and "
                              "λ there is the least-norm line load transferring the same forces. A lower lm "
                              "(line2) or a finer solid mesh avoids this", CouplingWarning, stacklevel=4)
            self._dependent = dep
        return self._dependent

    def solve_linear(self, A, b, x0=None, rtol=None):
        """Solve a reduced (Dirichlet DOFs removed) linear system of this model.

        ``rtol``: relative residual to reach (iterative solvers; default ``analysis.rtol``, what
        a linear analysis needs of its one solve). The solver's info dict is kept in
        ``last_linear_info`` (its ``note``, if any, says that a solver broke down and which one
        took over).
        """
        from .solvers.linear import solve_linear, solve_saddle
        rtol = self.scene.analysis["rtol"] if rtol is None else rtol
        method = self.linear_solver_method(len(b))
        self.counts[f"linear_solver.{method}"] += 1
        free = self.free
        # AMG aggregates 3×3 blocks only when every node keeps all or none of its components
        triplets = np.bincount(free // 3, minlength=self.n_unknowns // 3 + 1)
        block = 3 if np.isin(triplets, (0, 3)).all() else 1
        if not self.lagrange:
            options = dict(method=method, rtol=rtol)
            if method == "amg":
                options.update(near_nullspace=self.rigid_body_modes()[free], block_size=block)
                if self._auxiliary_space():
                    options.update(method="aux", **self._follow_split())
            x, info = solve_linear(A, b, **options)
            self.last_linear_info = info
            return x
        n = self.n_displacement_dofs
        primal = free < n
        p_idx = np.flatnonzero(primal)
        m_idx = np.flatnonzero(~primal)
        K = A[p_idx][:, p_idx]
        B = A[m_idx][:, p_idx]
        kappa = np.concatenate([np.repeat(g.operators.kappa[g.coupling.coupled], 3) for g in self.groups])
        solid = np.flatnonzero(free[p_idx] < 3 * self.n_solid_nodes)
        beam = np.flatnonzero(free[p_idx] >= 3 * self.n_solid_nodes)
        R = self.rigid_body_modes()[free[p_idx]]
        options = dict(method="direct" if method == "direct" else "block", solid=solid, beam=beam, near_nullspace=R,
                       rtol=rtol, block_size=block, dependent=self._dependent_multipliers(B, beam))
        if method != "direct" and self._auxiliary_space(lagrange=True) and len(solid) and len(beam):
            options["prolongation"] = self._follow_split()["prolongation"]
        # γ (augmentation and scaling of the constraint rows) from the operators, never the penalty
        x, lam, info = solve_saddle(K, B, kappa, b[p_idx], b[m_idx], **options)
        self.last_linear_info = info
        out = np.empty(len(b))
        out[p_idx], out[m_idx] = x, lam
        return out


# --------------------------------------------------------------------------------------------
# public entry points
# --------------------------------------------------------------------------------------------
def _as_scene(scene):
    if isinstance(scene, (str, bytes)) or hasattr(scene, "__fspath__"):
        return Scene.from_toml(scene)
    return scene


def plan(scene):
    """The effects :func:`solve` will run for ``scene``, in order (list of :class:`Effect`).

    Builds the meshes and resolves every set (supports, loads, fibre regions: a set that is
    unknown or selects nothing is reported here, as :func:`solve` would), assembles nothing.
    """
    return Model(_as_scene(scene)).effects()


def _print_step(record, index, _n):
    res = record.residuals[-1] if record.residuals else 0.0
    print(f"  step {index:4d}  load factor {record.load_factor:8.4f}  iterations {record.iterations:3d}  "
          f"residual {res:9.3e}" + (f"  (after {record.cuts} cut(s))" if record.cuts else "")
          + f"  {record.time:6.2f} s" + "".join(f"; {note}" for note in record.notes), flush=True)


def solve(scene, *, progress=False):
    """Run a scene: assemble what it needs, solve, return a :class:`~mortar1d3d.result.Result`.

    Parameters
    ----------
    scene : Scene or path to a TOML scene file
    progress : bool or callable
        True prints one line per load step; a callable gets ``(StepRecord, step_index, None)``.

    Raises
    ------
    SceneError
        Invalid scene, empty sets, or rigid-body motions not fixed (before any solve).
    ConvergenceError
        Newton's method gave up (message says where and what to try).

    Warns
    -----
    LargeDeformationWarning
        Linear kinematics, and a body moved by more than LINEAR_DISPLACEMENT_LIMIT of its size.
    """
    import time as _time

    from .result import Result
    from .solvers.newton import StepRecord, solve_load_steps
    start = _time.perf_counter()
    model = Model(_as_scene(scene)).prepare()
    callback = _print_step if progress is True else (progress or None)
    z0 = np.zeros(model.n_unknowns)
    if model.linear:
        model.counts["solver.linear"] += 1
        r0, K0 = model.residual(z0, 1.0)
        z = z0.copy()
        z[model.fixed] = model.prescribed(1.0)
        free = model.free
        rhs = -(r0 + K0 @ z)[free]
        z[free] += model.solve_linear(K0[free][:, free], rhs)
        model.last_residual = r0 + K0 @ z
        note = model.last_linear_info.get("note")
        record = StepRecord(load_factor=1.0, iterations=1,
                            residuals=[float(np.linalg.norm(r0[free] + (K0 @ z0)[free])),
                                       float(np.linalg.norm(model.last_residual[free]))],
                            increments=[float(np.linalg.norm(z[free]))], time=_time.perf_counter() - start,
                            notes=[note] if note else [])
        records, history = [record], [z.copy()]
        model.check_linear_displacements(z)
        if callback:
            callback(record, 1, 1)
    else:
        a = model.scene.analysis
        model.counts["solver.newton"] += 1
        z, records, history = solve_load_steps(model, z0, a["steps"], rtol=a["rtol"], increment_rtol=a["rtol"],
                                               max_iterations=a["max_iterations"], max_cuts=a["max_cuts"],
                                               progress=callback)
    return Result(model, z, records, history, wall_time=_time.perf_counter() - start)
