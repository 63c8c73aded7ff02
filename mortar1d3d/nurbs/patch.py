"""Trivariate NURBS patches and multi-patch solids with global (identified) control points.

A :class:`NurbsPatch` is a control net ``(n0, n1, n2, 3)`` with weights ``(n0, n1, n2)``, three open
knot vectors and three degrees. Its elements are the non-empty knot spans; each element becomes a
rational Bézier element on [-1, 1]³ by Bézier extraction (:meth:`NurbsPatch.bezier_elements`). A
:class:`NurbsSolid` is a list of patches whose coincident control points (same position and weight)
are one global control point: that is how patches are joined and how a closed pipe's seam is closed.
"""
from dataclasses import dataclass, field

import numpy as np

from . import knots as kv
from .basis import evaluate_bezier


def _homogeneous(control, weights):
    return np.concatenate([control * weights[..., None], weights[..., None]], axis=-1)


def merge_coincident(points, weights, tol=1e-10):
    """One id per group of coincident weighted points (same position to ``tol`` times the extent of
    ``points``, same weight to ``tol``), numbered in order of first appearance (so nothing is renumbered
    where nothing merges).

    Returns
    -------
    ids : (n,) int64
        The id of every point.
    first : (n_ids,) int64
        The first point of each id (``points[first]`` are the merged points).
    """
    extent = max(float(np.ptp(points, axis=0).max()), 1e-300)
    keys = np.round(np.column_stack([points / (tol * extent), weights / tol])).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank[inverse.ravel()], np.sort(first)


@dataclass(frozen=True, eq=False)
class NurbsPatch:
    """One trivariate NURBS patch.

    Attributes
    ----------
    control : (n0, n1, n2, 3) float64
        Control points (m).
    weights : (n0, n1, n2) float64
        Positive weights.
    knots : tuple of three float64 arrays
        Open knot vectors, ``len(knots[d]) = n_d + degrees[d] + 1``.
    degrees : tuple of three int
    """

    control: np.ndarray = field(repr=False)
    weights: np.ndarray = field(repr=False)
    knots: tuple = field(repr=False)
    degrees: tuple

    def __post_init__(self):
        control = np.ascontiguousarray(self.control, dtype=np.float64)
        weights = np.ascontiguousarray(self.weights, dtype=np.float64)
        if control.ndim != 4 or control.shape[3] != 3:
            raise ValueError(f"control: expected shape (n0, n1, n2, 3), got {control.shape}")
        if weights.shape != control.shape[:3]:
            raise ValueError(f"weights: expected shape {control.shape[:3]}, got {weights.shape}")
        if not np.isfinite(control).all() or not (np.isfinite(weights).all() and (weights > 0).all()):
            raise ValueError("control points must be finite and weights positive")
        degrees = tuple(int(p) for p in self.degrees)
        if len(degrees) != 3 or len(self.knots) != 3:
            raise ValueError("a trivariate patch needs three degrees and three knot vectors")
        knots = tuple(kv.check_knots(U, p, f"knots[{d}]") for d, (U, p) in enumerate(zip(self.knots, degrees)))
        for d in range(3):
            if kv.n_functions(knots[d], degrees[d]) != control.shape[d]:
                raise ValueError(f"knots[{d}]: {len(knots[d])} knots of degree {degrees[d]} make "
                                 f"{kv.n_functions(knots[d], degrees[d])} functions, the net has {control.shape[d]}")
        object.__setattr__(self, "control", control)
        object.__setattr__(self, "weights", weights)
        object.__setattr__(self, "knots", knots)
        object.__setattr__(self, "degrees", degrees)

    # -- sizes ----------------------------------------------------------------------------------
    @property
    def shape(self):
        """Control net size (n0, n1, n2)."""
        return self.weights.shape

    @property
    def n_control(self):
        return int(np.prod(self.shape))

    @property
    def element_shape(self):
        """Non-empty spans per direction."""
        return tuple(len(kv.spans(U, p)) for U, p in zip(self.knots, self.degrees))

    @property
    def n_elements(self):
        return int(np.prod(self.element_shape))

    # -- refinement -----------------------------------------------------------------------------
    def _transformed(self, direction, new_knots, new_degree, T):
        """The patch with the control net mapped by ``T`` (n_new, n_old) along ``direction``."""
        Pw = np.moveaxis(_homogeneous(self.control, self.weights), direction, 0)
        Pw = np.moveaxis(np.tensordot(T, Pw, axes=(1, 0)), 0, direction)
        knots = list(self.knots)
        knots[direction] = new_knots
        degrees = list(self.degrees)
        degrees[direction] = new_degree
        w = Pw[..., 3]
        return NurbsPatch(Pw[..., :3] / w[..., None], w, tuple(knots), tuple(degrees))

    def insert_knots(self, direction, new_knots):
        """h-refinement: the same geometry with ``new_knots`` inserted in ``direction`` (0, 1 or 2)."""
        U, T = kv.insertion_matrix(self.knots[direction], self.degrees[direction], new_knots)
        return self._transformed(direction, U, self.degrees[direction], T)

    def elevate(self, direction, times=1):
        """p-refinement: the same geometry with the degree in ``direction`` raised ``times`` times."""
        patch = self
        for _ in range(int(times)):
            U, T = kv.elevation_matrix(patch.knots[direction], patch.degrees[direction])
            patch = patch._transformed(direction, U, patch.degrees[direction] + 1, T)
        return patch

    def refine(self, splits=(2, 2, 2)):
        """Every span of direction d split into ``splits[d]`` equal parts (knot insertion)."""
        patch = self
        for d, m in enumerate(splits):
            U = patch.knots[d]
            k = kv.spans(U, patch.degrees[d])
            new = (U[k][:, None] + (U[k + 1] - U[k])[:, None] * (np.arange(1, int(m)) / int(m))[None, :]).ravel()
            if len(new):
                patch = patch.insert_knots(d, new)
        return patch

    # -- elements -------------------------------------------------------------------------------
    def element_functions(self):
        """Flat control-point ids (C order of the net) of each element's functions: (n_elements, n_local),
        elements numbered with the last direction fastest, functions in the Bézier order of
        :func:`mortar1d3d.nurbs.basis.rational_bernstein`."""
        firsts = [kv.extraction_operators(U, p)[1] for U, p in zip(self.knots, self.degrees)]
        p0, p1, p2 = self.degrees
        n0, n1, n2 = self.shape
        i, j, k = np.meshgrid(np.arange(p0 + 1), np.arange(p1 + 1), np.arange(p2 + 1), indexing="ij")
        out = []
        for f0 in firsts[0]:
            for f1 in firsts[1]:
                for f2 in firsts[2]:
                    out.append((((f0 + i) * n1 + (f1 + j)) * n2 + (f2 + k)).ravel())
        return np.array(out, dtype=np.int64)

    def _bezier_degrees(self, degrees):
        """The Bernstein degrees of :meth:`extraction`: the patch's own (None) or ``degrees``, each at least the
        patch's degree in its direction; ValueError otherwise."""
        if degrees is None:
            return self.degrees
        degrees = tuple(int(q) for q in degrees)
        if len(degrees) != 3 or any(q < p for q, p in zip(degrees, self.degrees)):
            raise ValueError(f"Bézier degrees {degrees}: expected three, each at least the patch's {self.degrees}")
        return degrees

    def extraction(self, degrees=None):
        """Per element the tensor extraction operator C (n_elements, n_local, n_bezier):
        ``N_{functions[e, i]} = Σ_a C[e, i, a] B_a`` (Bernstein polynomials on [-1, 1]³ of the patch's
        degrees, or of ``degrees`` (q0, q1, q2) >= them: the span's Bézier segment degree-elevated by
        :func:`~mortar1d3d.nurbs.knots.bernstein_elevation`, exact; n_bezier = Π (q_d + 1))."""
        degrees = self._bezier_degrees(degrees)
        C0, C1, C2 = (kv.extraction_operators(U, p)[0] for U, p in zip(self.knots, self.degrees))
        if degrees != self.degrees:
            C0, C1, C2 = (C @ kv.bernstein_elevation(p, q) for C, p, q in zip((C0, C1, C2), self.degrees, degrees))
        out = []
        for c0 in C0:
            for c1 in C1:
                for c2 in C2:
                    n_local = len(c0) * len(c1) * len(c2)
                    n_bezier = c0.shape[1] * c1.shape[1] * c2.shape[1]
                    out.append(np.einsum("ia,jb,kc->ijkabc", c0, c1, c2).reshape(n_local, n_bezier))
        return np.array(out)

    def bezier_elements(self, degrees=None):
        """Rational Bézier form of every element (of the patch's degrees, or degree-elevated to ``degrees``:
        the same rational functions, so the same geometry, in a larger Bernstein basis).

        With extraction C (n_local × n_bezier per element), the Bézier weights are ``w^b = Cᵀ w`` and
        the rational NURBS functions are ``R_i = Σ_a E[i, a] R^b_a`` with ``E[i, a] = C[i, a] w_i / w^b_a``
        (R^b: rational Bernstein functions with the weights w^b), so the Bézier control points are
        ``P^b = Eᵀ P``.

        Returns
        -------
        control : (n_elements, n_bezier, 3)
        weights : (n_elements, n_bezier)
        functions : (n_elements, n_local) int64
            Patch control-point ids (flat, C order) of each element's NURBS functions.
        E : (n_elements, n_local, n_bezier)
            The map above: Bézier control values = ``E[e].T @ values at the control points``.
        """
        functions = self.element_functions()
        C = self.extraction(degrees)
        P = self.control.reshape(-1, 3)[functions]
        w = self.weights.reshape(-1)[functions]
        wb = np.einsum("eia,ei->ea", C, w)
        E = C * w[:, :, None] / wb[:, None, :]
        control = np.einsum("eia,eix->eax", E, P)
        return control, wb, functions, E

    def element_ranges(self):
        """Parameter intervals of each element: (n_elements, 3, 2) lower and upper knot per direction."""
        ranges = []
        for U, p in zip(self.knots, self.degrees):
            k = kv.spans(U, p)
            ranges.append(np.stack([U[k], U[k + 1]], axis=1))
        out = [np.stack([r0, r1, r2]) for r0 in ranges[0] for r1 in ranges[1] for r2 in ranges[2]]
        return np.array(out)

    def evaluate(self, u):
        """Points x(u) of the patch at parameters ``u`` (m, 3) in the knot ranges (tensor Cox–de Boor,
        numpy: a reference independent of the Bézier route)."""
        u = np.atleast_2d(np.asarray(u, dtype=np.float64))
        B = [kv.bspline_values(U, p, u[:, d]) for d, (U, p) in enumerate(zip(self.knots, self.degrees))]
        Pw = _homogeneous(self.control, self.weights)
        hom = np.einsum("mi,mj,mk,ijkc->mc", B[0], B[1], B[2], Pw)
        return hom[:, :3] / hom[:, 3:]

    def evaluate_elements(self, xi):
        """Points x(ξ) of every element at the element parameters ``xi`` (q, 3) in [-1, 1]³ by the
        rational Bézier kernel: (n_elements, q, 3)."""
        control, wb, _, _ = self.bezier_elements()
        xi = np.broadcast_to(np.asarray(xi, dtype=np.float64), (len(control),) + np.shape(xi))
        x = np.empty(xi.shape)
        status = np.empty(len(control), dtype=np.int64)
        p0, p1, p2 = self.degrees
        evaluate_bezier(p0, p1, p2, np.ascontiguousarray(control), np.ascontiguousarray(wb), np.ascontiguousarray(xi),
                        x, status)
        return x

    def face_control(self, face):
        """Flat control-point ids of one patch face: ``face`` = ``"u0_min"``, ``"u0_max"``, ``"u1_min"``, …
        (the control points on that boundary surface of the patch, e.g. for Dirichlet conditions)."""
        try:
            axis = int(face[1])
            side = face[3:]
            if face[0] != "u" or side not in ("min", "max") or axis not in (0, 1, 2):
                raise ValueError
        except (ValueError, IndexError):
            raise ValueError(f"face {face!r}: expected 'u0_min', 'u0_max', 'u1_min', ..., 'u2_max'") from None
        ids = np.arange(self.n_control).reshape(self.shape)
        return np.take(ids, 0 if side == "min" else -1, axis=axis).ravel()


class NurbsSolid:
    """Patches with global control points: coincident control points (position to ``tol`` times the
    extent, equal weight) of any patches, or of one patch with itself (a closed pipe's seam), are one.

    Parameters
    ----------
    patches : list of NurbsPatch
    tol : float
        Relative tolerance of coincidence (see :func:`merge_coincident`).
    ids : list of int arrays, optional
        Given identification instead of coincidence: ``ids[k]`` (patch k's ``n_control``, flat C order)
        are labels, equal labels being one control point (e.g. the control-point ids of an input file).
        Control points with one label must coincide (position to ``tol`` times the extent, weight to
        ``tol``); ValueError naming the label otherwise. Global ids follow the labels' first appearance.

    Attributes
    ----------
    patches : list of NurbsPatch
    control : (n_control, 3) float64, weights : (n_control,) float64
        The global control points and weights.
    patch_ids : list of (patch.n_control,) int64
        Global id of every control point of each patch (flat, C order).
    """

    def __init__(self, patches, tol=1e-10, ids=None):
        self.patches = list(patches)
        if not self.patches:
            raise ValueError("NurbsSolid needs at least one patch")
        P = np.vstack([p.control.reshape(-1, 3) for p in self.patches])
        w = np.concatenate([p.weights.reshape(-1) for p in self.patches])
        if ids is None:
            ids, keep = merge_coincident(P, w, tol)
        else:
            ids, keep = _identified(P, w, ids, [p.n_control for p in self.patches], tol)
        self.control = P[keep]
        self.weights = w[keep]
        starts = np.cumsum([0] + [p.n_control for p in self.patches])
        self.patch_ids = [ids[a:b] for a, b in zip(starts[:-1], starts[1:])]

    @property
    def n_control(self):
        return len(self.weights)

    @property
    def n_elements(self):
        return sum(p.n_elements for p in self.patches)

    def face_control(self, patch, face):
        """Global control-point ids of face ``face`` of patch ``patch`` (see :meth:`NurbsPatch.face_control`)."""
        return np.unique(self.patch_ids[patch][self.patches[patch].face_control(face)])

    def __repr__(self):
        return f"NurbsSolid({len(self.patches)} patches, {self.n_elements} elements, {self.n_control} control points)"


def _identified(points, weights, labels, sizes, tol):
    """``(ids, first)`` as :func:`merge_coincident` returns them, from given labels per patch."""
    if len(labels) != len(sizes):
        raise ValueError(f"ids: expected one label array per patch ({len(sizes)}), got {len(labels)}")
    for k, (lab, n) in enumerate(zip(labels, sizes)):
        if np.shape(lab) != (n,):
            raise ValueError(f"ids[{k}]: expected {n} labels (the patch's control points), got shape {np.shape(lab)}")
    flat = np.concatenate([np.asarray(lab, dtype=np.int64) for lab in labels])
    _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    ids = rank[inverse.ravel()]
    first = np.sort(first)
    extent = max(float(np.ptp(points, axis=0).max()), 1e-300)
    gap = np.linalg.norm(points - points[first][ids], axis=1) / extent
    bad = np.flatnonzero((gap > tol) | (np.abs(weights - weights[first][ids]) > tol))
    if len(bad):
        raise ValueError(f"ids: the control points labelled {int(flat[bad[0]])} differ in position or weight "
                         f"(one label must be one control point)")
    return ids, first


__all__ = ["NurbsPatch", "NurbsSolid", "merge_coincident"]
