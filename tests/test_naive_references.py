"""The kernels against the slow, obvious references of tests/naive.py on small random scenes.

- element functions: the solid shape functions of the dispatch against monomial bases fitted to
  the reference nodes, the beam functions against the formulas of docs/conventions.md §2;
- broad phase: the candidate pairs of ``geometry.search`` contain every pair whose boxes from
  dense sampling overlap (brute force over all pairs) and every pair the beam really enters, and
  so do the pairs left after the hull planes;
- segmentation: the segments of ``assemble_mortar(..., integration="segment")`` against the owner
  of densely sampled centreline points, each located in every solid element by lattice search
  and ``scipy.optimize.root``;
- D, M, κ: against adaptive quadrature (``scipy.integrate.quad_vec``) of the mortar integrands
  over every segment.

Scenes: the unit cube in 2 × 2 × 2 cells of every solid element type with moved interior nodes
(curved faces), random helix pieces as Hermite, ``line`` or ``line3`` beams, some of them
leaving the cube. Seeds are fixed.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import generate
from mortar1d3d.elements import beam as beam_types
from mortar1d3d.elements.solid import dispatch
from mortar1d3d.geometry.context import KernelInput
from mortar1d3d.geometry.search import beam_bounding_boxes, find_candidate_pairs, solid_bounding_boxes

import naive

SOLID_TYPES = list(dispatch.NODAL_ELEMENTS)     # nurbs27: test_nurbs_engine
BEAM_TYPES = ["hermite", "line", "line3"]


def scene_solid(element, seed=1):
    """The unit cube, 2³ grid cells of ``element``, interior nodes moved by 0.15 of a cell."""
    return generate.distort(generate.box((0, 0, 0), (1, 1, 1), (2, 2, 2), element), 0.15, seed=seed)


def scene_beams(kind, seed, count=2, elements=3, upper=1.0):
    """``count`` random helix pieces in the box [0, upper]³ (upper > 1: partly outside the cube) as
    ``kind`` beams: Hermite, or Lagrange through the Hermite nodes (line3: and the midpoints)."""
    hermite = generate.random_curved_beams(count, elements, seed=seed, upper=(upper,) * 3)
    if kind == "hermite":
        return hermite
    if kind == "line":
        return m13.BeamMesh.lagrange(hermite.positions, hermite.elements, "line")
    middle = np.vstack([hermite.evaluate(e, [0.0]) for e in range(hermite.n_elements)])
    elements = np.column_stack([hermite.elements, hermite.n_nodes + np.arange(hermite.n_elements)])
    return m13.BeamMesh.lagrange(np.vstack([hermite.positions, middle]), elements, "line3")


# -- element functions ------------------------------------------------------------------------------

@pytest.mark.parametrize("name", SOLID_TYPES)
def test_solid_shape_functions_equal_the_monomial_reference(name):
    d = dispatch.SOLID_ELEMENTS[name]
    rng = np.random.default_rng(5)
    lower, upper = naive.parameter_box(d.family)
    xi = np.vstack([rng.uniform(lower - 0.2, upper + 0.2, (40, 3)), d.reference_nodes])
    N_ref, dN_ref = naive.shape_values(name, xi)
    N, dN = np.empty(dispatch.MAX_NODES), np.empty((dispatch.MAX_NODES, 3))
    for q, x in enumerate(xi):
        dispatch.shape(d.code, x, N)
        dispatch.deriv(d.code, x, dN)
        np.testing.assert_allclose(N[: d.n_nodes], N_ref[q], rtol=0, atol=1e-13)
        np.testing.assert_allclose(dN[: d.n_nodes], dN_ref[q], rtol=0, atol=1e-13)


@pytest.mark.parametrize("kind", BEAM_TYPES)
def test_beam_functions_equal_the_formulas(kind):
    t = beam_types.BEAM_ELEMENTS[kind]
    H, dH = np.empty(4), np.empty(4)
    for eta in np.linspace(-1.0, 1.0, 11):
        for L in (0.3, 2.5):
            beam_types.shape(t.code, eta, L, H)
            beam_types.deriv(t.code, eta, L, dH)
            H_ref, dH_ref = naive.beam_shape(kind, eta, L)
            np.testing.assert_allclose(H[: t.n_functions], H_ref[:, 0], rtol=0, atol=1e-15)
            np.testing.assert_allclose(dH[: t.n_functions], dH_ref[:, 0], rtol=0, atol=1e-15)


# -- broad phase -------------------------------------------------------------------------------------

def candidate_matrix(beams, solid):
    """Boolean (n_beam_elements, n_solid_elements) of the candidate pairs of ``geometry.search``."""
    offsets, solids = find_candidate_pairs(beam_bounding_boxes(beams)[0], solid_bounding_boxes(solid)[0])
    pairs = np.zeros((beams.n_elements, solid.n_elements), dtype=bool)
    for e in range(beams.n_elements):
        pairs[e, solids[offsets[e]:offsets[e + 1]]] = True
    return pairs


def padded(boxes, fraction):
    """``boxes`` grown by ``fraction`` of their diagonal on every side."""
    pad = fraction * np.linalg.norm(boxes[:, 1] - boxes[:, 0], axis=1)[:, None]
    return np.stack([boxes[:, 0] - pad, boxes[:, 1] + pad], axis=1)


# every solid type once, every beam type twice
SCENES = [("hexahedron", "hermite"), ("hexahedron20", "line3"), ("hexahedron27", "line"), ("tetra", "line3"),
          ("tetra10", "hermite"), ("tetra10", "line")]


@pytest.mark.parametrize("element, kind", SCENES)
def test_candidate_pairs_contain_every_overlap_and_every_entered_element(element, kind):
    solid = scene_solid(element, seed=3)
    beams = scene_beams(kind, seed=4, upper=1.4)                     # some pieces outside the cube
    found = candidate_matrix(beams, solid)
    sampled = naive.brute_force_pairs(naive.sampled_beam_boxes(beams), naive.sampled_solid_boxes(solid))
    entered = naive.entered_pairs(beams, solid)
    assert entered.any() and not entered.all()
    # boxes from samples lie inside the elements' hulls: each of their overlaps is a candidate
    assert not (sampled & ~found).any(), np.argwhere(sampled & ~found)
    assert not (entered & ~found).any(), np.argwhere(entered & ~found)
    # and the conservative boxes are not much larger than the sampled ones (control polygons
    # stand off the curve by a fraction of the element size)
    loose = naive.brute_force_pairs(padded(naive.sampled_beam_boxes(beams), 0.25),
                                    padded(naive.sampled_solid_boxes(solid), 0.25))
    assert not (found & ~loose).any(), np.argwhere(found & ~loose)


@pytest.mark.parametrize("element, kind", SCENES)
def test_hull_pairs_keep_every_entered_element(element, kind):
    """The pairs of the kernel context (the box overlaps less those a solid element's hull planes
    separate, ``search.hull_pairs``) still hold every pair the beam enters, and the planes drop
    pairs where boxes of oblique elements overlap."""
    solid = scene_solid(element, seed=3)
    beams = scene_beams(kind, seed=4, upper=1.4)
    ctx = KernelInput(beams, solid)
    kept = np.zeros((beams.n_elements, solid.n_elements), dtype=bool)
    for e in range(beams.n_elements):
        kept[e, ctx.pair_solid[ctx.pair_offsets[e]:ctx.pair_offsets[e + 1]]] = True
    boxes = candidate_matrix(beams, solid)
    entered = naive.entered_pairs(beams, solid)
    assert not (entered & ~kept).any(), np.argwhere(entered & ~kept)
    assert not (kept & ~boxes).any()
    if element.startswith("tetra"):
        assert np.count_nonzero(kept) < 0.8 * np.count_nonzero(boxes), (np.count_nonzero(kept), np.count_nonzero(boxes))


# -- segmentation ------------------------------------------------------------------------------------

MARGIN = 1e-6      # samples this close (in η) to a segment end may belong to either side


def assert_segments_follow_the_samples(ops, beams, solid, samples=41):
    """Every sample's owner is the owner of the segment it lies in (-1 in gaps), away from segment
    ends; every sampled change of owner has a segment end within that sample spacing; the
    midpoint of every segment (also of pieces shorter than the spacing) is owned by the segment's
    element."""
    eta, owner = naive.sampled_owners(beams, solid, samples)
    elements = naive.solid_elements(solid)
    for e in range(beams.n_elements):
        seg = np.sort(ops.segments[ops.segments["beam_element"] == e], order="eta_start")
        ends = np.concatenate([seg["eta_start"], seg["eta_end"]])
        expected = np.full(samples, -1)
        for row in seg:
            expected[(eta >= row["eta_start"]) & (eta <= row["eta_end"])] = row["solid_element"]
        clear = np.abs(eta[:, None] - ends[None, :]).min(axis=1, initial=np.inf) > MARGIN
        np.testing.assert_array_equal(owner[e, clear], expected[clear], err_msg=f"beam element {e}: {seg}")
        for i in np.flatnonzero(owner[e, 1:] != owner[e, :-1]):
            assert ((ends >= eta[i]) & (ends <= eta[i + 1])).any(), (e, eta[i], seg)
        if len(seg):
            mid = 0.5 * (seg["eta_start"] + seg["eta_end"])
            np.testing.assert_array_equal(naive.owners(elements, naive.centreline(beams, e, mid)[0]),
                                          seg["solid_element"])


@pytest.mark.parametrize("element, kind", SCENES)
def test_segments_agree_with_dense_sampling(element, kind):
    solid = scene_solid(element)
    beams = scene_beams(kind, seed=2, upper=1.3)
    ops = m13.assemble_mortar(beams, solid, integration="segment")
    assert len(ops.segments) > beams.n_elements                     # the beams cross faces
    assert 0 < ops.embedded_length < 0.999 * ops.beam_length          # and leave the cube
    assert_segments_follow_the_samples(ops, beams, solid)


# -- D, M, κ by adaptive quadrature ------------------------------------------------------------------

def operator_error(ops, D, M, kappa):
    """Largest entry difference of D, M and κ over the largest entry of the reference, the worst of
    the three (every scalar entry of D and M is a 3×3 identity block: each diagonal checked)."""
    Dd, Md = ops.D.toarray(), ops.M.toarray()
    errors = [np.abs(ops.kappa - kappa).max() / np.abs(kappa).max()]
    for i in range(3):
        errors.append(np.abs(Dd[i::3, i::3] - D).max() / np.abs(D).max())
        errors.append(np.abs(Md[i::3, i::3] - M).max() / np.abs(M).max())
    return max(errors)


@pytest.mark.parametrize("element, kind, lm, upper", [
    ("hexahedron", "hermite", "line2", 1.3),
    ("hexahedron20", "line3", "line3", 1.0),
    ("hexahedron27", "hermite", "line4", 1.0),
    ("tetra", "line", "line3", 1.3),
    ("tetra10", "hermite", "line2", 1.3),
    ("tetra10", "line3", "line4", 1.0),
])
def test_operators_equal_adaptive_quadrature(element, kind, lm, upper):
    """20 Gauss points per segment: the rule's error on these curved pieces is below round-off."""
    solid = scene_solid(element, seed=5)
    beams = scene_beams(kind, seed=7, count=1, upper=upper)
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=20, lm=lm)
    assert len(ops.segments) > beams.n_elements                     # the beam crosses faces
    assert (ops.embedded_length < 0.999 * ops.beam_length) == (upper > 1.0)     # and leaves the cube
    D, M, kappa = naive.adaptive_operators(beams, solid, ops.segments, lm)
    assert operator_error(ops, D, M, kappa) <= 1e-12


def test_adaptive_quadrature_sees_a_rule_that_is_too_short():
    """The same comparison fails for 2 Gauss points per segment on curved pieces."""
    solid = scene_solid("hexahedron27", seed=5)
    beams = scene_beams("hermite", seed=7, count=1)
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=2, lm="line3")
    D, M, kappa = naive.adaptive_operators(beams, solid, ops.segments, "line3")
    assert operator_error(ops, D, M, kappa) > 1e-6
