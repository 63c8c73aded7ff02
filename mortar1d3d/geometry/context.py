"""The kernel context: the flat arrays every stage after the search works on.

A :class:`KernelInput` is built once per ``assemble_mortar`` call, in the reference
configuration, from a :class:`~mortar1d3d.mesh.BeamMesh` and a :class:`~mortar1d3d.mesh.SolidMesh`.
The stages that follow read it: the segmentation (:mod:`~mortar1d3d.geometry.segmentation`), the
integration points (:mod:`~mortar1d3d.integration.points`) and the assembly
(:mod:`~mortar1d3d.mortar.assemble`). They change nothing in it but the one-to-one certificates of
``linear``, each computed the first time a decision needs it (the same value whichever stage or
worker computes it).
Kernels take its arrays one by one (Numba compiles for arrays, not for this class).
"""
import numpy as np

from .._schedule import workers
from ..elements.solid.dispatch import HULL_TEST
from .projection import linear_maps
from .search import beam_frames, find_candidate_pairs, hull_pairs, solid_frames, solid_hulls


class KernelInput:
    """Solid frames, linear maps, beam frames and candidate pairs of one scene.

    Coordinates are local where round-off matters: every solid element's nodes relative to its
    first node (``solid_origin``), every beam element's coefficients relative to its first node
    (``beam_origin``); kernels shift between the two frames by the difference of the origins
    (see :mod:`~mortar1d3d.geometry.projection`). n = solid elements, m = beam elements (of this
    context: all of them, or the subset of :meth:`beam_subset`), n_pairs = candidate pairs.

    Attributes
    ----------
    points : (n_nodes, 3) or (n_nodes, 4) float64
        Solid node coordinates (``solid.kernel_points``, global frame; column 3: weights of rational elements).
    codes : (n,) int64
        Element code of every solid element (``solid.element_codes``).
    conn : (n, m) int64
        Solid connectivity, padded with -1 (``solid.connectivity``, as wide as its largest element).
    solid_boxes : (n, 2, 3) float64
        Padded bounding boxes [min, max] of the solid elements (Bernstein control points).
    solid_h : (n,) float64
        Element size h (box diagonal before padding): the unit of every relative tolerance.
    solid_origin : (n, 3) float64
        Each solid element's first node: the origin of its local frame.
    hull : (n, MAX_FACES, 4) float64
        Half-spaces n·x <= c (unit normal, offset; local frame) containing each solid element with a
        margin, one along each face (:func:`~.search.solid_hulls`): a tighter bound than the box for
        elements oblique to the axes, tested per pair and per point before a Newton projection
        (zero rows, no bound, for the types whose descriptor sets ``hull_test`` False: hex8, and for
        the elements of no box pair, which no kernel tests).
    linear : (n, 5, 3) float64
        Each element's map linearised at its centre and inverted (exact for affine elements):
        the table of :func:`~mortar1d3d.geometry.projection.linear_maps`, whose certificate entries
        the kernels fill on first use (:func:`~mortar1d3d.geometry.projection.certified_outside`).
    Q : (m, 4, 3) float64
        Centreline coefficients of ``r(η) = Σ H_k q_k`` relative to ``beam_origin`` (positions
        relative, tangents as they are; unused rows zero).
    beam_origin : (m, 3) float64
        Each beam element's first node: the origin of its local frame.
    beam_boxes : (m, 2, 3) float64
        Padded bounding boxes of the beam elements (Bézier control points).
    lengths : (m,) float64
        Reference lengths L of the beam elements (the Hermite tangents' scale).
    beam_code : int
        Beam element code (one type per mesh).
    pair_offsets : (m + 1,) int64
        Candidate pairs as CSR over the beam elements: the solid elements whose boxes overlap
        beam element e's and whose hull no plane separates from its control points
        (:func:`~.search.hull_pairs`) are ``pair_solid[pair_offsets[e]:pair_offsets[e + 1]]``...
    pair_solid : (n_pairs,) int64
        ...ascending within each beam element (the lowest-index ownership rule relies on it).
    beam_ids : (m,) int64
        The global index of each beam element of this context (``arange(m)`` unless a subset).

    Notes
    -----
    Built in this order: solid frames (boxes, sizes, origins; :func:`~.search.solid_frames`),
    linear maps (:func:`~.projection.linear_maps`), beam frames (:func:`~.search.beam_frames`),
    candidate pairs from the boxes (:func:`~.search.find_candidate_pairs`), the hulls of the elements
    of those pairs (:func:`~.search.solid_hulls`), and the pairs less those the hulls separate
    (:func:`~.search.hull_pairs`).
    """

    def __init__(self, beams, solid):
        self.points = solid.kernel_points
        self.codes = solid.element_codes
        self.conn = solid.connectivity
        self.solid_boxes, self.solid_h, self.solid_origin = solid_frames(solid)
        self.linear = np.empty((solid.n_elements, 5, 3))
        linear_maps(self.points, self.conn, self.codes, self.solid_origin, self.solid_h, self.linear, workers())
        self.Q, self.beam_origin, self.beam_boxes, _ = beam_frames(beams)
        self.lengths = beams.lengths
        self.beam_code = beams.element_type.code
        self.pair_offsets, self.pair_solid = find_candidate_pairs(self.beam_boxes, self.solid_boxes)
        # planes only for the elements of candidate pairs: no kernel tests another element's hull
        self.hull = solid_hulls(self.points, self.conn, self.codes, self.solid_origin, self.solid_h,
                                elements=self.pair_solid)
        if HULL_TEST[self.codes].any():
            self.pair_offsets, self.pair_solid = hull_pairs(self.pair_offsets, self.pair_solid, self.hull,
                                                            self.solid_origin, self.beam_code, self.Q, self.lengths,
                                                            self.beam_origin, self.beam_boxes)
        self.beam_ids = np.arange(beams.n_elements)

    @property
    def n_beam(self):
        """Beam elements of this context (m)."""
        return len(self.pair_offsets) - 1

    def pair_beam(self):
        """(n_pairs,) the beam element (of this context) of every candidate pair."""
        return np.repeat(np.arange(self.n_beam), np.diff(self.pair_offsets))

    def beam_subset(self, elements):
        """The context of the beam elements ``elements`` (sorted indices into this one, not empty).

        The solid arrays are shared; the beam arrays and the candidate pairs are those of
        ``elements``, renumbered 0..len(elements)-1, and ``beam_ids`` maps back to the global
        index (for segments of re-segmented beam elements, :func:`~.segmentation.resegment`).
        """
        sub = object.__new__(KernelInput)
        sub.__dict__.update(self.__dict__)
        sub.beam_ids = self.beam_ids[elements]
        counts = self.pair_offsets[elements + 1] - self.pair_offsets[elements]
        sub.pair_offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        sub.pair_solid = np.concatenate([self.pair_solid[self.pair_offsets[e]:self.pair_offsets[e + 1]]
                                         for e in elements]).astype(np.int64)
        sub.Q = np.ascontiguousarray(self.Q[elements])
        sub.lengths = np.ascontiguousarray(self.lengths[elements])
        sub.beam_origin = np.ascontiguousarray(self.beam_origin[elements])
        sub.beam_boxes = np.ascontiguousarray(self.beam_boxes[elements])
        return sub
