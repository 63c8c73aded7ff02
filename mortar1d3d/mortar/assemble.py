"""``assemble_mortar``: the mortar operators D, M and κ of beams embedded in a solid.

Per (beam element, solid element) group of integration points g (docs/conventions.md §1):

    D[j, k] += Σ_g Φ_j(η_g) H_k(η_g) w_g        M[j, a] += Σ_g Φ_j(η_g) N_a(ξ_g) w_g
    κ[j]    += Σ_g Φ_j(η_g) w_g                  w_g = Gauss weight · (η_b - η_a)/2 · |r0'(η_g)|

and every scalar entry stands for a 3×3 identity block.
"""
import time
import warnings
from dataclasses import InitVar, dataclass, field
from functools import partial

import numpy as np

from .._borrowed import borrowed
from .._config import CHUNK, announce_compilation, njit, njit_inline
from .._memory import carve
from .._parallel import in_parallel
from .._schedule import claim, n_chunks, new_claims, workers
from ..elements.multiplier import multiplier as multiplier_type
from ..elements.multiplier import shape as lm_shape
from ..elements.beam import MAX_FUNCTIONS
from ..elements.beam import n_functions as beam_n_functions
from ..elements.beam import shape as beam_shape
from ..elements.solid import dispatch as solid_types
from ..geometry.auto_segments import auto_segments
from ..geometry.context import KernelInput
from ..geometry.segmentation import segment
from ..integration.points import (POINT_INSIDE, POINT_NOT_CONVERGED, POINT_OUTSIDE, boundary_segmented_points,
                                  checked_segment_points, element_points, exact_rule_counts, segment_points)
from ..mesh import BeamMesh, SolidMesh
from .sparse import gathered_block_csr, relative_residual, row_sources

SEGMENT_DTYPE = np.dtype([("beam_element", np.int64), ("solid_element", np.int64),
                          ("eta_start", np.float64), ("eta_end", np.float64)])
POINT_DTYPE = np.dtype([("beam_element", np.int64), ("solid_element", np.int64), ("eta", np.float64),
                        ("xi", np.float64, (3,)), ("weight", np.float64), ("position", np.float64, (3,)),
                        ("status", np.int64)])
INTEGRATIONS = ("segment", "element", "auto", "element_boundary")


@dataclass
class MortarOperators:
    """The coupling operators and what produced them.

    Attributes
    ----------
    D : scipy.sparse.csr_matrix, (3 n_lm, n_beam_centreline_dofs)
    M : scipy.sparse.csr_matrix, (3 n_lm, 3 n_solid_nodes)
    kappa : (n_lm,) float64
        κ_j = ∫ Φ_j ds; zero for LM nodes that no integration point touched.
    segments : structured array (SEGMENT_DTYPE)
        Segment-based: the pieces [eta_start, eta_end] of beam elements inside one solid
        element. Element-based: one row per (beam element, solid element) group of points,
        spanning the η of its first and last point.
    points : structured array (POINT_DTYPE)
        The integration points that were assembled (η, ξ, weight incl. ``|r0'|``, position); built
        on first access from ``point_fields`` (its columns as separate arrays).
    n_integration_points : int
    embedded_length : float
        Σκ, the beam length that is coupled (certificate: compare with the beam length inside
        the solid).
    beam_length : float
        Total reference length of the beams.
    constraint_residual : float
        ‖D q_B − M X_S‖ / ‖D q_B‖ at the reference positions: round-off for any correct
        integration, since both sides integrate Φ_j times the same point. Computed on first
        access (its kernel is compiled then, not in every first run; an assembly does not pay
        for the pass over D and M unless the certificate is read); the constructor takes the
        value or a function of no arguments returning it.
    diagnostics : dict
        Counts: candidate pairs, face crossings, points not converged / outside their element;
        segment-based also ``segmentation_fallbacks`` (beam elements whose pieces failed the
        tiling check and were segmented again with more search points),
        ``segmentation_bisections`` (of those, segmented by bisection of the owner along η) and
        ``segmentation_unresolved`` (still failing: a warning is issued).
    timings : dict
        Wall time in seconds per stage (search, segmentation, integration, assembly, csr).
    """

    D: object
    M: object
    kappa: np.ndarray
    segments: np.ndarray
    point_fields: dict
    n_lm: int
    integration: str
    n_gauss: int
    lm: str
    embedded_length: float
    beam_length: float
    constraint_residual: InitVar[object]
    diagnostics: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    def __post_init__(self, constraint_residual):
        self._points = None
        self._constraint_residual = constraint_residual

    @property
    def points(self):
        if self._points is None:
            table = np.empty(len(self.point_fields["eta"]), dtype=POINT_DTYPE)
            for name, values in self.point_fields.items():
                table[name] = values
            self._points = table
        return self._points

    def _residual(self):
        if callable(self._constraint_residual):
            self._constraint_residual = float(self._constraint_residual())
        return self._constraint_residual

    @property
    def n_integration_points(self):
        return len(self.point_fields["eta"])

    @property
    def coupled_lm_nodes(self):
        """Boolean mask (n_lm,) of LM nodes with κ > 0."""
        return self.kappa > 0.0

    def __repr__(self):
        return (f"MortarOperators({self.integration}-based, n_gauss={self.n_gauss}, lm={self.lm}: "
                f"D {self.D.shape} nnz {self.D.nnz}, M {self.M.shape} nnz {self.M.nnz}, "
                f"{len(self.segments)} segments, {self.n_integration_points} points, "
                f"embedded length {self.embedded_length:.6g} of {self.beam_length:.6g}, "
                f"residual {self.constraint_residual:.2e})")


def _constraint_residual(D, M, positions, tangents, points):
    """``MortarOperators.constraint_residual`` of copies of the meshes' positions taken at assembly (a mesh
    moved afterwards does not change it): q_B in the layout of ``BeamMesh.centreline_dofs`` ([r_0, t_0, r_1,
    ...] with tangents), the same values, built without that method's parallel kernel, which a first run
    would otherwise compile for this diagnostic alone."""
    q = positions.ravel() if tangents is None else np.concatenate((positions, tangents), axis=1).ravel()
    return relative_residual(D, q, M, points.ravel())


#: computed on first access (see the class's docstring); the dataclass's InitVar of the same name is the
#: constructor's argument, a value or a function returning it
MortarOperators.constraint_residual = property(MortarOperators._residual,
                                               doc="‖D q_B − M X_S‖ / ‖D q_B‖, computed on first access")


@njit
def _group_operators(group_start, p_beam, p_solid, eta, xi, weight, beam_code, lengths, n_phi,
                     codes, conn, points, m_offsets, D_local, M_local, kappa_local, workers):
    """Local D, M and κ of every group of points (``conn``, ``points``: a rational element's weights)."""
    claims = new_claims(group_start.shape[0] - 1, workers)
    _group_operators_workers(workers, claims, group_start, p_beam, p_solid, eta, xi, weight, beam_code, lengths, n_phi,
                             codes, conn, points, m_offsets, D_local, M_local, kappa_local)


@njit
def _group_operators_worker(worker, claims, group_start, p_beam, p_solid, eta, xi, weight, beam_code, lengths, n_phi,
                            codes, conn, points, m_offsets, D_local, M_local, kappa_local):
    n_groups = group_start.shape[0] - 1
    nH = beam_n_functions(beam_code)
    Phi = np.empty(4)
    H = np.empty(MAX_FUNCTIONS)
    N = np.empty(solid_types.MAX_NODES)
    Dg = np.empty((4, MAX_FUNCTIONS))
    Mg = np.empty((4, solid_types.MAX_NODES))
    kg = np.empty(4)
    begin, stop = claim(claims, n_groups, worker)
    while begin < stop:
        _group_operators_chunk(begin, stop, group_start, p_beam, p_solid, eta, xi, weight, beam_code, lengths,
                               n_phi, codes, conn, points, m_offsets, D_local, M_local, kappa_local, Dg, Mg,
                               kg, Phi, H, N, nH)
        begin, stop = claim(claims, n_groups, worker)


@njit_inline
def _group_operators_chunk(begin, stop, group_start, p_beam, p_solid, eta, xi, weight, beam_code, lengths, n_phi,
                           codes, conn, points, m_offsets, D_local, M_local, kappa_local, Dg, Mg, kg, Phi, H, N, nH):
    # the caller holds every array for this call: the calls per point pass them without reference
    # counting (see mortar1d3d._borrowed)
    (group_start, p_beam, p_solid, eta, xi, weight, lengths, codes, conn, points, m_offsets, D_local, M_local,
     kappa_local, Dg, Mg, kg, Phi, H, N) = borrowed(group_start, p_beam, p_solid, eta, xi, weight, lengths, codes, conn,
                                                   points, m_offsets, D_local, M_local, kappa_local, Dg, Mg, kg, Phi, H,
                                                   N)
    for g in range(begin, stop):
        e = p_beam[group_start[g]]
        s = p_solid[group_start[g]]
        nN = solid_types.n_nodes(codes[s])
        # a call per point only for rational elements (their weights)
        rational = solid_types.RATIONAL[codes[s]]
        Dg[:] = 0.0
        Mg[:] = 0.0
        kg[:] = 0.0
        for q in range(group_start[g], group_start[g + 1]):
            lm_shape(n_phi, eta[q], Phi)
            beam_shape(beam_code, eta[q], lengths[e], H)
            solid_types.shape(codes[s], xi[q], N)
            if rational:
                solid_types.weighted_values(codes[s], conn[s], points, N)
            w = weight[q]
            for j in range(n_phi):
                wj = w * Phi[j]
                kg[j] += wj
                for k in range(nH):
                    Dg[j, k] += wj * H[k]
                for a in range(nN):
                    Mg[j, a] += wj * N[a]
        for j in range(n_phi):
            kappa_local[g, j] = kg[j]
            for k in range(nH):
                D_local[g, j * nH + k] = Dg[j, k]
            base = m_offsets[g] + j * nN
            for a in range(nN):
                M_local[base + a] = Mg[j, a]


#: the kernel's workers run on the package's one parallel loop (see mortar1d3d._parallel); the worker, compiled
#: on its own and called through a symbol, inlines its loop body (``njit_inline``), which is optimised once
_group_operators_workers = in_parallel(_group_operators_worker)


@njit
def _status_counts(status, p_solid):
    """Points not converged, outside their segment's element, and not owned by any element."""
    not_converged = outside = uncoupled = 0
    for q in range(status.shape[0]):
        if status[q] == POINT_NOT_CONVERGED:
            not_converged += 1
        elif status[q] == POINT_OUTSIDE:
            outside += 1
        if p_solid[q] < 0:
            uncoupled += 1
    return not_converged, outside, uncoupled


@njit
def _groups(p_beam, p_solid, codes, n_phi, n_beam):
    """Groups of points: runs with the same (beam element, solid element).

    Returns ``group_start`` (n_groups + 1), the offsets of each group's local M entries
    (``n_phi`` rows of the owner's nodes) and ``beam_groups`` (n_beam + 1): points come ordered
    by beam element, so the groups of element e are ``beam_groups[e]:beam_groups[e + 1]``.
    """
    n = p_beam.shape[0]
    count = 0
    for q in range(n):
        if q == 0 or p_beam[q] != p_beam[q - 1] or p_solid[q] != p_solid[q - 1]:
            count += 1
    group_start = np.empty(count + 1, dtype=np.int64)
    m_offsets = np.empty(count + 1, dtype=np.int64)
    beam_groups = np.zeros(n_beam + 1, dtype=np.int64)
    m_offsets[0] = 0
    g = 0
    for q in range(n):
        if q == 0 or p_beam[q] != p_beam[q - 1] or p_solid[q] != p_solid[q - 1]:
            group_start[g] = q
            m_offsets[g + 1] = m_offsets[g] + n_phi * solid_types.N_NODES[codes[p_solid[q]]]
            beam_groups[p_beam[q] + 1] += 1
            g += 1
    group_start[count] = n
    for e in range(n_beam):
        beam_groups[e + 1] += beam_groups[e]
    return group_start, m_offsets, beam_groups


@njit
def _kappa(src_offsets, src, n_phi, beam_groups, kappa_local, kappa):
    _kappa_parts(n_chunks(src_offsets.shape[0] - 1, CHUNK), src_offsets, src, n_phi, beam_groups, kappa_local, kappa)


@njit
def _kappa_part(c, src_offsets, src, n_phi, beam_groups, kappa_local, kappa):
    # the rows of chunk c (a parallel loop over the rows in chunks: one call per chunk)
    for r in range(c * CHUNK, min(src_offsets.shape[0] - 1, (c + 1) * CHUNK)):
        v = 0.0
        for t in range(src_offsets[r], src_offsets[r + 1]):
            e = src[t] // n_phi
            j = src[t] % n_phi
            for g in range(beam_groups[e], beam_groups[e + 1]):
                v += kappa_local[g, j]
        kappa[r] = v


_kappa_parts = in_parallel(_kappa_part)


def lm_numbering(beams, lm_type):
    """(n_beam_elements, 4) LM node of each multiplier function, and the number of LM nodes.

    Beam nodes first with their own index, then interior LM nodes element by element.
    """
    m = beams.n_elements
    index = np.full((m, 4), -1, dtype=np.int64)
    index[:, 0] = beams.elements[:, 0]
    index[:, 1] = beams.elements[:, 1]
    n_int = lm_type.n_interior
    for i in range(n_int):
        index[:, 2 + i] = beams.n_nodes + n_int * np.arange(m) + i
    return index, beams.n_nodes + n_int * m


def _check_int(name, value, low, high):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def assemble_mortar(beams, solid, integration="segment", n_gauss=6, lm="line2", search_points=6):
    """Mortar operators D, M and κ coupling ``beams`` to ``solid`` (docs/conventions.md §1).

    Parameters
    ----------
    beams : BeamMesh
    solid : SolidMesh
    integration : {"segment", "element", "auto", "element_boundary"}
        Segment-based: Gauss points on each piece of a beam element inside one solid element
        (exact up to quadrature). Element-based: Gauss points on the whole beam element, each
        owned by the lowest-index solid element that contains it. Element_boundary:
        element-based, except that the beam elements crossing the solid's boundary (a Gauss point
        or an end in no solid element) are segmented, so that their part outside is left out
        exactly (4C's ``gauss_point_projection_boundary_segmentation``; see
        :func:`~mortar1d3d.integration.points.boundary_segmented_points`). Auto: segment-based results
        at close to element-based cost: beam elements certified to lie inside one solid element
        are not cut (their points are the element-based ones), the others are cut at their face
        crossings (closed form for straight beams in affine elements); segments where the
        integrand is a polynomial (straight beam in tet4 / parallelepiped hex8 / affine quadratic
        elements) get the minimal exact Gauss rule instead of ``n_gauss``.
    n_gauss : int
        Gauss points per segment (segment-based, auto where not polynomial, the segmented beam
        elements of element_boundary) or per beam element (element-based).
    lm : {"line2", "line3", "line4"}
        Lagrange multiplier interpolation.
    search_points : int
        Start points along each beam element for the face intersections (>= 2).

    Returns
    -------
    MortarOperators

    Notes
    -----
    Steinbrecher, Mayr, Grill, Kremheller, Meier, Popp (2020), A mortar-type finite element
    approach for embedding 1D beams into 3D solid volumes, Comput Mech 66:1377-1398.
    Geometry is evaluated once, in the reference configuration.
    """
    if not isinstance(beams, BeamMesh):
        raise TypeError(f"beams must be a BeamMesh, got {type(beams).__name__}")
    if not isinstance(solid, SolidMesh):
        raise TypeError(f"solid must be a SolidMesh, got {type(solid).__name__}")
    if integration not in INTEGRATIONS:
        raise ValueError(f"integration must be one of {INTEGRATIONS}, got {integration!r}")
    n_gauss = _check_int("n_gauss", n_gauss, 1, 64)
    search_points = _check_int("search_points", search_points, 2, 64)
    try:
        lm_type = multiplier_type(lm)
    except ValueError as exc:
        raise ValueError(f"lm: {exc}") from None

    announce_compilation()
    timings = {}
    t0 = time.perf_counter()
    ctx = KernelInput(beams, solid)
    t1 = time.perf_counter()
    timings["search"] = t1 - t0
    diagnostics = {"candidate_pairs": len(ctx.pair_solid)}

    if integration == "auto":
        seg_beam, seg_solid, seg_start, seg_end, beam_affine, auto_info = auto_segments(ctx, search_points)
        counts, auto_info["exact_rule_segments"] = exact_rule_counts(ctx, seg_beam, seg_solid, beam_affine,
                                                                     lm_type.n_functions, n_gauss)
        diagnostics.update(auto_info)
        t2 = time.perf_counter()
        timings["segmentation"] = t2 - t1
        p_beam, p_solid, eta, xi, weight, position, status = segment_points(
            ctx, seg_beam, seg_solid, seg_start, seg_end, counts)
    elif integration == "segment":
        *segments, bad = segment(ctx, search_points, diagnostics)
        t2 = time.perf_counter()
        timings["segmentation"] = t2 - t1
        # the fallback (beam elements whose pieces or points fail are segmented again) runs with the points
        (seg_beam, seg_solid, seg_start, seg_end), (p_beam, p_solid, eta, xi, weight, position, status) = \
            checked_segment_points(ctx, segments, bad, n_gauss, search_points, diagnostics)
    elif integration == "element_boundary":
        t2 = t1
        timings["segmentation"] = 0.0
        p_beam, p_solid, eta, xi, weight, position, status = boundary_segmented_points(ctx, n_gauss, search_points,
                                                                                       diagnostics)
    else:
        t2 = t1
        timings["segmentation"] = 0.0
        p_beam, p_solid, eta, xi, weight, position, status = element_points(ctx, n_gauss)
    t3 = time.perf_counter()
    timings["integration_points"] = t3 - t2

    not_converged, outside, uncoupled = _status_counts(status, p_solid)
    diagnostics["points_not_converged"] = not_converged
    diagnostics["points_outside_element"] = outside
    if integration in ("element", "element_boundary"):
        diagnostics["points_uncoupled"] = uncoupled
    if diagnostics.get("segmentation_unresolved"):
        warnings.warn(f"assemble_mortar: the segments of {diagnostics['segmentation_unresolved']} beam elements "
                      "do not tile their embedded part even after the bisection fallback",
                      RuntimeWarning, stacklevel=2)
    if not_converged:
        warnings.warn(f"assemble_mortar: {not_converged} integration points did not converge in their "
                      "solid element's projection and were left out", RuntimeWarning, stacklevel=2)
    if outside:
        warnings.warn(f"assemble_mortar: {outside} integration points of segments lie outside their "
                      "solid element (a missed face crossing?)", RuntimeWarning, stacklevel=2)
    if not_converged or uncoupled:
        keep = (status == POINT_INSIDE) | (status == POINT_OUTSIDE)
        p_beam, p_solid, eta, xi, weight, position, status = (
            a[keep] for a in (p_beam, p_solid, eta, xi, weight, position, status))

    n_phi = lm_type.n_functions
    nH = beam_n_functions.py_func(ctx.beam_code)
    group_start, m_offsets, beam_groups = _groups(p_beam, p_solid, ctx.codes, n_phi, beams.n_elements)
    n_groups = len(group_start) - 1
    g_solid = p_solid[group_start[:-1]]
    D_local, M_local, kappa_local = carve(((n_groups, n_phi * nH), np.float64), (m_offsets[-1], np.float64),
                                          ((n_groups, n_phi), np.float64))
    _group_operators(group_start, p_beam, p_solid, eta, xi, weight, ctx.beam_code, ctx.lengths, n_phi, ctx.codes,
                     ctx.conn, ctx.points,
                     m_offsets, D_local, M_local, kappa_local, workers())
    lm_index, n_lm = lm_numbering(beams, lm_type)
    src_offsets, src = row_sources(lm_index, n_phi, n_lm)
    kappa = np.empty(n_lm)
    _kappa(src_offsets, src, n_phi, beam_groups, kappa_local, kappa)
    t4 = time.perf_counter()
    timings["assembly"] = t4 - t3
    # D: group g's columns are its beam element's coefficient columns; M: its solid element's nodes
    g_beam = p_beam[group_start[:-1]]
    D = gathered_block_csr(src_offsets, src, n_phi, beam_groups, np.arange(n_groups, dtype=np.int64) * (n_phi * nH),
                           np.full(n_groups, nH, dtype=np.int64), beams.function_columns(), g_beam, D_local.ravel(),
                           (n_lm, beams.n_centreline_dofs // 3))
    M = gathered_block_csr(src_offsets, src, n_phi, beam_groups, m_offsets[:-1],
                           solid_types.N_NODES[ctx.codes[g_solid]], ctx.conn, g_solid, M_local, (n_lm, solid.n_nodes))
    t5 = time.perf_counter()
    timings["csr"] = t5 - t4

    if integration in ("segment", "auto"):
        segments = np.empty(len(seg_beam), dtype=SEGMENT_DTYPE)
        segments["beam_element"], segments["solid_element"] = seg_beam, seg_solid
        segments["eta_start"], segments["eta_end"] = seg_start, seg_end
    else:
        segments = np.empty(n_groups, dtype=SEGMENT_DTYPE)
        segments["beam_element"] = g_beam
        segments["solid_element"] = g_solid
        segments["eta_start"] = eta[group_start[:-1]]
        segments["eta_end"] = eta[group_start[1:] - 1]
    point_fields = {"beam_element": p_beam, "solid_element": p_solid, "eta": eta, "xi": xi, "weight": weight,
                    "position": position, "status": status}
    residual = partial(_constraint_residual, D, M, beams.positions.copy(),
                       None if beams.tangents is None else beams.tangents.copy(), solid.points.copy())
    timings["total"] = time.perf_counter() - t0
    return MortarOperators(D=D, M=M, kappa=kappa, segments=segments, point_fields=point_fields, n_lm=n_lm,
                           integration=integration, n_gauss=n_gauss, lm=lm_type.name,
                           embedded_length=float(kappa.sum()), beam_length=beams.length,
                           constraint_residual=residual, diagnostics=diagnostics, timings=timings)
