"""Segments, D, M and κ against hand-computed values.

A. Segment-based integration: the pieces [η_a, η_b] of beam elements inside one solid element
   against closed-form face crossings (straight beams through hex rows and tets, a cubic Hermite
   crossing a face, beams through a node / along an edge / in a face, tangential touches,
   leaving and re-entering an element, beams partly outside the solid).
B. D, M and κ of straight beams on the axis of the unit hex8 in closed form (exact polynomial
   integration written here, independent of the library), for line2/line3/line4 multipliers,
   Hermite and Lagrange beams, segment- and element-based integration.
C. Element-based integration: ownership of Gauss points (lowest index), dropped outside points.

Straight Hermite beams whose nodal tangents are the unit chord direction have L = chord and
r(η) = (r1 + r2)/2 + η L/2 d exactly (the cubic terms cancel), so their crossings are linear
equations in η.
"""
import numpy as np
import pytest
from numpy.polynomial import Polynomial as P

from mortar1d3d import BeamMesh, assemble_mortar, generate

from naive import (LM_NODES, arc_length, cell_owners, grid_chord_pieces, hermite_curve, hermite_polys, integrate,
                   lagrange_polys, tet_chord_pieces)

# --------------------------------------------------------------------------------------------
# helpers (independent of the library; the polynomials and arc lengths are in tests/naive.py)
# --------------------------------------------------------------------------------------------
ETA = P([0.0, 1.0])


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def straight_beam(a, b):
    """One Hermite element from a to b, unit tangents along the chord."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = unit(b - a)
    return BeamMesh.hermite([a, b], [d, d], [[0, 1]])


def seg_list(ops):
    s = ops.segments
    return [(int(b), int(e), float(a0), float(a1)) for b, e, a0, a1 in
            zip(s["beam_element"], s["solid_element"], s["eta_start"], s["eta_end"])]


def assert_segments(ops, expected, tol=1e-12):
    """expected: list of (beam_element, solid_element, eta_start, eta_end), in the library's order."""
    got = seg_list(ops)
    assert len(got) == len(expected), f"got {got}, expected {expected}"
    for g, e in zip(got, expected):
        assert g[:2] == e[:2], f"got {got}, expected {expected}"
        assert abs(g[2] - e[2]) <= tol and abs(g[3] - e[3]) <= tol, f"got {got}, expected {expected}"


def assert_no_overlap(ops):
    s = ops.segments
    for e in np.unique(s["beam_element"]):
        rows = np.sort(s[s["beam_element"] == e], order="eta_start")
        assert np.all(rows["eta_end"] > rows["eta_start"])
        assert np.all(rows["eta_end"][:-1] <= rows["eta_start"][1:])
        assert rows["eta_start"][0] >= -1.0 and rows["eta_end"][-1] <= 1.0


# --------------------------------------------------------------------------------------------
# A1. straight beam through a row of hex8
# --------------------------------------------------------------------------------------------
def test_straight_beam_through_hex_row():
    solid = generate.box((0, 0, 0), (4, 1, 1), (4, 1, 1))
    a, b = np.array([0.3, 0.15, 0.8]), np.array([3.6, 0.85, 0.25])
    beams = straight_beam(a, b)
    L = np.linalg.norm(b - a)
    assert beams.lengths[0] == pytest.approx(L, rel=1e-14)
    ops = assemble_mortar(beams, solid)
    # x(η) = 0.3 + (η + 1)/2 · 3.3 = k  <=>  η = 2 (k - 0.3)/3.3 - 1
    cuts = [-1.0] + [2.0 * (k - 0.3) / 3.3 - 1.0 for k in (1, 2, 3)] + [1.0]
    assert_segments(ops, [(0, s, cuts[s], cuts[s + 1]) for s in range(4)], tol=1e-12)
    seg = ops.segments
    assert np.sum(0.5 * (seg["eta_end"] - seg["eta_start"]) * L) == pytest.approx(L, rel=1e-14)
    assert ops.embedded_length == pytest.approx(L, rel=1e-13)
    assert ops.beam_length == pytest.approx(L, rel=1e-14)
    assert ops.constraint_residual < 1e-13
    assert ops.n_integration_points == 4 * 6


def test_straight_beam_in_hex_row_spanning_several_beam_elements():
    """Three beam elements on one straight line; cuts at x = 1, 2, 3 fall in elements 0, 1, 2."""
    solid = generate.box((0, 0, 0), (4, 1, 1), (4, 1, 1))
    a, b = np.array([0.3, 0.15, 0.8]), np.array([3.6, 0.85, 0.25])
    d = unit(b - a)
    xs = np.array([0.3, 1.4, 2.5, 3.6])                 # nodes (x), cuts at 1 (el 0), 2 (el 1), 3 (el 2)
    pos = a + ((xs - 0.3) / 3.3)[:, None] * (b - a)
    beams = BeamMesh.hermite(pos, np.tile(d, (4, 1)), [[0, 1], [1, 2], [2, 3]])
    ops = assemble_mortar(beams, solid)
    c = lambda x, e: 2.0 * (x - xs[e]) / 1.1 - 1.0  # noqa: E731
    assert_segments(ops, [(0, 0, -1.0, c(1, 0)), (0, 1, c(1, 0), 1.0),
                          (1, 1, -1.0, c(2, 1)), (1, 2, c(2, 1), 1.0),
                          (2, 2, -1.0, c(3, 2)), (2, 3, c(3, 2), 1.0)], tol=1e-12)
    assert ops.embedded_length == pytest.approx(np.linalg.norm(b - a), rel=1e-13)


# --------------------------------------------------------------------------------------------
# A2. curved Hermite beam crossing x = 1
# --------------------------------------------------------------------------------------------
def test_curved_hermite_crossing_a_face():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    r1, r2 = np.array([0.3, 0.2, 0.3]), np.array([1.8, 0.8, 0.6])
    t1, t2 = unit([0.6, 0.7, 0.4]), unit([1.0, -0.5, 0.3])
    beams = BeamMesh.hermite([r1, r2], [t1, t2], [[0, 1]])
    L = beams.lengths[0]
    curve = hermite_curve(r1, t1, r2, t2, L)
    # L is the arc length of the curve it defines; the library's fixed point uses a 10-point
    # Gauss rule (docs/conventions.md §2), which is 1.2e-12 off the exact integral for this curve
    assert arc_length(beams, 0, -1.0, 1.0, 60) == pytest.approx(L, rel=1e-11)
    # x(η) is a genuine cubic, increasing on [-1, 1], inside the slab in y and z
    x = curve[0]
    assert abs(x.coef[3]) > 1e-2
    eta_fine = np.linspace(-1, 1, 2001)
    assert np.all(x.deriv()(eta_fine) > 0)
    assert np.all((curve[1](eta_fine) > 0.01) & (curve[1](eta_fine) < 0.99))
    assert np.all((curve[2](eta_fine) > 0.01) & (curve[2](eta_fine) < 0.99))
    roots = np.roots((x - 1.0).coef[::-1])
    real = [r.real for r in roots if abs(r.imag) < 1e-12 and -1 <= r.real <= 1]
    assert len(real) == 1
    eta_cut = real[0]
    assert abs(x(eta_cut) - 1.0) < 1e-14
    for n_gauss, rtol in ((6, 1e-7), (16, 1e-13)):
        ops = assemble_mortar(beams, solid, n_gauss=n_gauss)
        assert_segments(ops, [(0, 0, -1.0, eta_cut), (0, 1, eta_cut, 1.0)], tol=1e-10)
        # Σ weights per segment = the arc length of the segment (Gauss on a smooth speed)
        pts = ops.points
        for s, (lo, hi) in enumerate([(-1.0, eta_cut), (eta_cut, 1.0)]):
            w = pts["weight"][pts["solid_element"] == s].sum()
            assert w == pytest.approx(arc_length(beams, 0, lo, hi, 60), rel=rtol)
        assert ops.constraint_residual < 1e-13


# --------------------------------------------------------------------------------------------
# A3. through a node, along an edge, in a face (2x2x2 hexes of size 1)
# --------------------------------------------------------------------------------------------
NODE = np.array([1.0, 1.0, 1.0])
D_NODE = unit([1.0, 0.8, 0.6])
DEGENERATE_BEAMS = {
    # name: (start, end) of a straight beam; expected pieces and owners: grid_chord_pieces
    "through_node": (NODE - 0.7 * D_NODE, NODE + 0.9 * D_NODE),
    "along_edge_z": ((1.0, 1.0, 0.3), (1.0, 1.0, 1.8)),         # edge x=y=1: 4 hexes each side of z=1
    "along_edge_x": ((0.25, 1.0, 1.0), (1.9, 1.0, 1.0)),        # edge y=z=1
    "along_edge_upper": ((1.0, 1.0, 1.2), (1.0, 1.0, 1.9)),     # only elements 4..7 contain it
    "in_face_x1": ((1.0, 0.2, 0.3), (1.0, 1.7, 0.6)),           # face x = 1, crosses y = 1
    "in_face_z1": ((0.3, 1.4, 1.0), (1.6, 1.8, 1.0)),           # face z = 1, crosses x = 1
    "in_face_no_cut": ((0.2, 1.2, 1.0), (0.8, 1.9, 1.0)),       # face z = 1 inside cells 2 / 6
    "on_boundary_face": ((0.2, 0.3, 0.0), (1.7, 0.4, 0.0)),     # outer face z = 0
}


@pytest.mark.parametrize("name", list(DEGENERATE_BEAMS))
def test_degenerate_positions_counted_once(name):
    solid = generate.box((0, 0, 0), (2, 2, 2), (2, 2, 2))
    a, b = DEGENERATE_BEAMS[name]
    beams = straight_beam(a, b)
    L = np.linalg.norm(np.subtract(b, a))
    ops = assemble_mortar(beams, solid)
    expected = grid_chord_pieces(a, b)
    assert_segments(ops, expected, tol=1e-12)
    assert_no_overlap(ops)
    assert ops.embedded_length == pytest.approx(L, rel=1e-13)
    assert ops.kappa.sum() == pytest.approx(L, rel=1e-13)
    assert ops.constraint_residual < 1e-13


def test_degenerate_owners_spelled_out():
    """The owners of the named cases, written by hand (the generic check above derives them)."""
    solid = generate.box((0, 0, 0), (2, 2, 2), (2, 2, 2))
    owners = {"through_node": [0, 7], "along_edge_z": [0, 4], "along_edge_x": [0, 1],
              "along_edge_upper": [4], "in_face_x1": [0, 2], "in_face_z1": [2, 3],
              "in_face_no_cut": [2], "on_boundary_face": [0, 1]}
    for name, want in owners.items():
        a, b = DEGENERATE_BEAMS[name]
        ops = assemble_mortar(straight_beam(a, b), solid)
        assert list(ops.segments["solid_element"]) == want, name
    # through the node: the cut is where the chord passes the node (s = 0.7 of 1.6)
    a, b = DEGENERATE_BEAMS["through_node"]
    ops = assemble_mortar(straight_beam(a, b), solid)
    assert ops.segments["eta_end"][0] == pytest.approx(2 * 0.7 / 1.6 - 1, abs=1e-12)


# --------------------------------------------------------------------------------------------
# A4. tangential touch of a face, from outside and from inside
# --------------------------------------------------------------------------------------------
def _arch(x_ends, bulge, c=0.6, z0=0.2, z1=0.8):
    """Hermite arch in the plane y = 0.5 from z = z0 to z = z1, both nodes at x = x_ends.

    Tangents (∓sign c, 0, s) (unit). By symmetry x(η) = x_ends - sign · c L/4 (1 - η²) with
    sign = +1 for bulge "down" (towards -x), -1 for "up"; L does not depend on x_ends.
    Returns beams and the centreline polynomials.
    """
    s = np.sqrt(1 - c * c)
    sign = 1.0 if bulge == "down" else -1.0
    t1, t2 = np.array([-sign * c, 0.0, s]), np.array([sign * c, 0.0, s])
    r1, r2 = np.array([x_ends, 0.5, z0]), np.array([x_ends, 0.5, z1])
    beams = BeamMesh.hermite([r1, r2], [t1, t2], [[0, 1]])
    L = beams.lengths[0]
    curve = hermite_curve(r1, t1, r2, t2, L)
    eta = np.linspace(-1, 1, 401)
    np.testing.assert_allclose(curve[0](eta), x_ends - sign * c * L / 4 * (1 - eta ** 2), rtol=0, atol=1e-15)
    assert np.all((curve[2](eta) >= min(z0, z1) - 1e-15) & (curve[2](eta) <= max(z0, z1) + 1e-15))
    return beams, curve


def _arch_length(c=0.6, z0=0.2, z1=0.8):
    beams, _ = _arch(2.0, "down", c, z0, z1)
    return beams.lengths[0]


# Tangential touches: the face Newton polishes a converged crossing to a parameter step of 1e-11; two
# crossings of the same face with the centreline on that face in between (a double root, found as
# several close cuts) are a touch: those pieces join a neighbour that contains them, or stay uncoupled
# when the beam touches from outside (segmentation._tile). Without this the touch gave a segment
# [-3.05e-6, 3.05e-6] (and with the earlier rule, any piece shorter than 1e-6 in η between crossings
# was taken for a touch: issue 16, see the corner cuts below).


def test_touching_a_face_from_outside():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    c = 0.6
    L = _arch_length(c)
    beams, curve = _arch(1.0 + c * L / 4, "down", c)       # min x = 1 at η = 0: touches x = 1
    assert beams.lengths[0] == L
    assert abs(curve[0](0.0) - 1.0) < 1e-15
    ops = assemble_mortar(beams, solid)
    assert len(ops.segments) == 0, seg_list(ops)
    assert ops.embedded_length == 0.0
    assert np.all(ops.kappa == 0.0)
    assert ops.n_integration_points == 0


def test_touching_a_face_from_inside():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    c = 0.6
    L = _arch_length(c)
    beams, curve = _arch(1.0 - c * L / 4, "up", c)         # max x = 1 at η = 0
    assert abs(curve[0](0.0) - 1.0) < 1e-15
    ops = assemble_mortar(beams, solid)
    assert_segments(ops, [(0, 0, -1.0, 1.0)], tol=0.0)
    assert ops.embedded_length == pytest.approx(L, rel=1e-6)   # 6 Gauss points on a curved speed
    ops20 = assemble_mortar(beams, solid, n_gauss=20)
    assert ops20.embedded_length == pytest.approx(L, rel=1e-12)


def test_touching_a_face_from_outside_element_based():
    """No Gauss point of the arch is inside (η = 0 is not a 6-point Gauss point)."""
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    c = 0.6
    L = _arch_length(c)
    beams, _ = _arch(1.0 + c * L / 4, "down", c)
    ops = assemble_mortar(beams, solid, integration="element")
    assert ops.n_integration_points == 0 and len(ops.segments) == 0
    assert ops.embedded_length == 0.0 and ops.diagnostics["points_uncoupled"] == 6


def test_touching_a_shared_face_from_one_side():
    """Two hexes; the arch lies in element 1 and touches the shared face x = 1: one segment."""
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    c = 0.6
    L = _arch_length(c)
    beams, _ = _arch(1.0 + c * L / 4, "down", c)
    ops = assemble_mortar(beams, solid)
    assert_segments(ops, [(0, 1, -1.0, 1.0)], tol=0.0)


def test_touching_a_shared_face_counts_the_length_once():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    c = 0.6
    L = _arch_length(c)
    beams, _ = _arch(1.0 + c * L / 4, "down", c)
    ops = assemble_mortar(beams, solid, n_gauss=20)
    assert_no_overlap(ops)
    assert ops.embedded_length == pytest.approx(arc_length(beams, 0, -1.0, 1.0, 60), rel=1e-12)
    assert ops.segments["eta_start"].min() == -1.0 and ops.segments["eta_end"].max() == 1.0


def _poking_arch(depth, c=0.6):
    """The arch inside the unit cube whose apex pokes out through x = 1 by ``depth`` (< 0: stays inside)."""
    L = _arch_length(c)
    beams, curve = _arch(1.0 + depth - c * L / 4, "up", c)
    return beams, curve, L


@pytest.mark.parametrize("depth", [1e-2, 1e-5, 1e-8, 1e-11, 1e-13])
def test_a_shallow_excursion_through_a_face_follows_the_geometry(depth):
    """The piece outside has length ~ sqrt(depth): decided by the face condition at every depth (the
    earlier rule dropped excursions shorter than 1e-6 in η, i.e. deeper than ~1e-13 here but coupled
    the part outside the solid for depths below ~1e-13 ... 1e-12)."""
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams, curve, L = _poking_arch(depth)
    half = np.sqrt(4 * depth / (0.6 * L))                 # x(±half) = 1
    assert abs(curve[0](half) - 1.0) < 1e-14
    ops = assemble_mortar(beams, solid, n_gauss=20)
    inside = arc_length(beams, 0, -1.0, -half, 60) + arc_length(beams, 0, half, 1.0, 60)
    # the roots of a near-double root are determined to ~ round-off / (curvature · half-width)
    assert ops.embedded_length == pytest.approx(inside, rel=1e-12, abs=1e-14 / half)
    assert len(ops.segments) == 2


@pytest.mark.parametrize("depth", [0.0, -1e-13, -1e-9])
def test_an_arch_touching_a_face_from_inside_stays_whole(depth):
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams, _, L = _poking_arch(depth)
    ops = assemble_mortar(beams, solid, n_gauss=20)
    assert_segments(ops, [(0, 0, -1.0, 1.0)], tol=0.0)
    assert ops.embedded_length == pytest.approx(arc_length(beams, 0, -1.0, 1.0, 60), rel=1e-13)


# --------------------------------------------------------------------------------------------
# A4b. corner and edge cuts at every depth (issue 16): no threshold in the beam element's η
# --------------------------------------------------------------------------------------------
def _corner_cut(s):
    """A straight beam element of length 2 in the plane z = 0.5 crossing the edge x = y = 1 of the unit
    cube at 45°, on the line x + y = 2 - s: for s > 0 it cuts off a piece of chord √2 s, for s <= 0 it
    passes outside (at distance |s|/√2 from the edge)."""
    mid = np.array([1.0 - 0.5 * s, 1.0 - 0.5 * s, 0.5])
    d = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    return straight_beam(mid - d, mid + d)


UNIT_CUBE = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))


@pytest.mark.parametrize("integration", ["segment", "auto"])
def test_corner_cut_at_every_depth(integration):
    """Issue 16: a cut of depth 5e-7 (s = 6.9e-7, chord 9.8e-7 < 1e-6 in η) coupled nothing: a piece
    shorter than 1e-6 in the beam's η between crossings was taken for a tangential touch."""
    for s in [6.9e-7] + [10.0 ** -k for k in range(1, 14)]:
        ops = assemble_mortar(_corner_cut(s), UNIT_CUBE, integration=integration)
        assert ops.embedded_length == pytest.approx(np.sqrt(2) * s, rel=1e-9, abs=1e-15), s
        assert len(ops.segments) == 1
    for s in [0.0] + [-(10.0 ** -k) for k in range(1, 15)]:
        ops = assemble_mortar(_corner_cut(s), UNIT_CUBE, integration=integration)
        assert ops.embedded_length == 0.0 and len(ops.segments) == 0, s


@pytest.mark.parametrize("centre", [0.0, 7.0710678e-7, 1e-11, -1e-11, -5e-10, 5e-10])
def test_corner_cut_is_continuous_across_every_threshold(centre):
    """Sweeping the cut in steps of 1e-13 (h = √3) across the former sliver threshold (chord 1e-6), the
    tangency s = 0, and the bands of the crossing (5e-10 beyond the face, in parameter units 1e-9) and of
    the ownership (1e-11): κ, D and M change by O(step) each time, never by a jump."""
    step = 1e-13
    full = assemble_mortar(_corner_cut(1.0), UNIT_CUBE)          # a cut through the whole cube
    previous = None
    for k in range(-6, 7):
        s = centre + k * step
        ops = assemble_mortar(_corner_cut(s), UNIT_CUBE)
        assert ops.embedded_length == pytest.approx(np.sqrt(2) * max(s, 0.0), rel=1e-6, abs=2e-15)
        if previous is not None:
            for name in ("D", "M"):
                change = abs(getattr(ops, name) - getattr(previous, name)).max() / abs(getattr(full, name)).max()
                assert change <= 4 * step, (s, name, change)
            assert abs(ops.kappa - previous.kappa).max() <= 4 * step
        previous = ops


def test_a_long_beam_element_keeps_its_small_pieces():
    """Issue 16: one beam element of length 200 over a row of 100 hex8 (h = 2) lost pieces of 1e-4 h (1e-6
    in its η, the former sliver length). The element runs along the row, nearly parallel to its edge
    y = 0, z = 2, and cuts that edge's corner of the cross-section: y = t, z = t + 2 - s, inside for
    0 < t < s, a piece of length s |d| / d_y with d = (100, 1, 1)."""
    solid = generate.box((0, 0, 0), (200, 2, 2), (100, 1, 1))
    d = np.array([100.0, 1.0, 1.0])
    for s in (1e-4, 1e-6, 1e-8):
        centre = np.array([101.0, 0.0, 2.0 - s])                 # t = 0 here
        ops = assemble_mortar(straight_beam(centre - d, centre + d), solid)
        assert ops.embedded_length == pytest.approx(s * np.linalg.norm(d), rel=1e-9), s
        assert list(ops.segments["solid_element"]) == [50]


# --------------------------------------------------------------------------------------------
# A5. leaving and re-entering one element
# --------------------------------------------------------------------------------------------
def _u_beam():
    """Arch bulging to +x from x = 0.9: x(η) = 0.9 + c L/4 (1 - η²) crosses x = 1 at ±η*."""
    c = 0.9
    beams, curve = _arch(0.9, "up", c, 0.1, 0.9)
    L = beams.lengths[0]
    assert 0.9 + c * L / 4 > 1.1
    eta_star = np.sqrt(1.0 - 0.1 * 4.0 / (c * L))
    assert abs(curve[0](eta_star) - 1.0) < 1e-14 and abs(curve[0](-eta_star) - 1.0) < 1e-14
    return beams, curve, eta_star


def test_leaving_and_reentering_one_element():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams, _, es = _u_beam()
    ops = assemble_mortar(beams, solid, n_gauss=20)
    assert_segments(ops, [(0, 0, -1.0, -es), (0, 0, es, 1.0)], tol=1e-10)
    # exact arc lengths (60-point Gauss); beams.lengths uses 10 points and is 2e-10 off here
    inside = arc_length(beams, 0, -1.0, -es, 60) + arc_length(beams, 0, es, 1.0, 60)
    assert ops.embedded_length == pytest.approx(inside, rel=1e-12)
    assert ops.embedded_length < 0.3 * beams.lengths[0]


def test_leaving_into_the_neighbour_and_back():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    beams, _, es = _u_beam()
    ops = assemble_mortar(beams, solid, n_gauss=20)
    assert_segments(ops, [(0, 0, -1.0, -es), (0, 1, -es, es), (0, 0, es, 1.0)], tol=1e-10)
    assert ops.embedded_length == pytest.approx(arc_length(beams, 0, -1.0, 1.0, 60), rel=1e-12)
    assert ops.embedded_length == pytest.approx(beams.lengths[0], rel=1e-9)


# --------------------------------------------------------------------------------------------
# A6. partly outside
# --------------------------------------------------------------------------------------------
def test_partly_outside_straight_beam():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    a, b = np.array([-0.5, 0.2, 0.3]), np.array([1.5, 0.7, 0.9])
    beams = straight_beam(a, b)
    L = np.linalg.norm(b - a)
    ops = assemble_mortar(beams, solid)
    e0 = 2 * 0.5 / 2.0 - 1.0                                   # x = 0
    e1 = 2 * 1.5 / 2.0 - 1.0                                   # x = 1
    assert_segments(ops, [(0, 0, e0, e1), (0, 1, e1, 1.0)], tol=1e-12)
    inside = L * 1.5 / 2.0
    assert ops.embedded_length == pytest.approx(inside, rel=1e-10)
    # κ_j = L/2 ∫_{e0}^{1} Φ_j dη, Φ_0 = (1-η)/2 (outside node), Φ_1 = (1+η)/2
    k0 = 0.5 * L * integrate(P([0.5, -0.5]), e0, 1.0)
    k1 = 0.5 * L * integrate(P([0.5, 0.5]), e0, 1.0)
    np.testing.assert_allclose(ops.kappa, [k0, k1], rtol=1e-12)
    assert ops.kappa[0] < ops.kappa[1]
    full = assemble_mortar(straight_beam(a + [0.6, 0, 0], b + [0.4, 0, 0]), solid)
    assert full.kappa[0] == pytest.approx(full.kappa[1], rel=1e-13)


def test_beam_entirely_outside():
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    ops = assemble_mortar(straight_beam((1.5, 0.2, 0.3), (2.5, 0.7, 0.9)), solid)
    assert len(ops.segments) == 0 and ops.embedded_length == 0.0
    assert ops.D.nnz == 0 and ops.M.nnz == 0


def test_partly_outside_crossing_through_the_solid():
    """Enters at x = 0, leaves at x = 2: outside at both ends."""
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    a, b = np.array([-0.4, 0.1, 0.2]), np.array([2.6, 0.9, 0.7])
    beams = straight_beam(a, b)
    L = np.linalg.norm(b - a)
    ops = assemble_mortar(beams, solid)
    c = lambda x: 2 * (x + 0.4) / 3.0 - 1.0  # noqa: E731
    assert_segments(ops, [(0, 0, c(0), c(1)), (0, 1, c(1), c(2))], tol=1e-12)
    assert ops.embedded_length == pytest.approx(2.0 / 3.0 * L, rel=1e-12)


# --------------------------------------------------------------------------------------------
# A (tets). straight beam through Kuhn-split cells
# --------------------------------------------------------------------------------------------
def test_straight_beam_through_tets():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1), "tetra")
    a, b = np.array([0.1, 0.2, 0.3]), np.array([1.9, 0.75, 0.85])
    beams = straight_beam(a, b)
    L = np.linalg.norm(b - a)
    ops = assemble_mortar(beams, solid)
    expected = tet_chord_pieces(solid, a, b)
    assert len(expected) >= 4
    order = np.argsort(ops.segments["eta_start"])
    got = [seg_list(ops)[i] for i in order]
    assert [g[1] for g in got] == [e[1] for e in expected]
    for g, e in zip(got, expected):
        assert abs(g[2] - e[2]) < 1e-12 and abs(g[3] - e[3]) < 1e-12
    # the segments tile [-1, 1]
    assert got[0][2] == -1.0 and got[-1][3] == 1.0
    assert all(got[i][3] == got[i + 1][2] for i in range(len(got) - 1))
    seg = ops.segments
    assert np.sum(0.5 * (seg["eta_end"] - seg["eta_start"]) * L) == pytest.approx(L, rel=1e-14)
    assert ops.embedded_length == pytest.approx(L, rel=1e-13)
    assert ops.constraint_residual < 1e-13


def test_straight_beam_partly_outside_tets():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1), "tetra")
    a, b = np.array([-0.3, 0.2, 0.3]), np.array([1.7, 0.75, 0.85])
    beams = straight_beam(a, b)
    L = np.linalg.norm(b - a)
    ops = assemble_mortar(beams, solid)
    expected = tet_chord_pieces(solid, a, b)
    order = np.argsort(ops.segments["eta_start"])
    got = [seg_list(ops)[i] for i in order]
    assert [g[1] for g in got] == [e[1] for e in expected]
    for g, e in zip(got, expected):
        assert abs(g[2] - e[2]) < 1e-12 and abs(g[3] - e[3]) < 1e-12
    assert got[0][2] == pytest.approx(2 * 0.3 / 2.0 - 1.0, abs=1e-12)
    assert ops.embedded_length == pytest.approx(L * 1.7 / 2.0, rel=1e-12)


# --------------------------------------------------------------------------------------------
# B. D, M, κ in closed form on the axis of the unit hex8
# --------------------------------------------------------------------------------------------
def _axis_beams(kind, layout):
    """Beams on the line y = z = 0.5 of [0,1]^3.

    layout "pieces": two elements, node order scrambled: node 0 at x = 0.2, 1 at x = 0.9, 2 at
    x = 0.5; elements [0, 2] and [2, 1] (line3: middle nodes 3 at x = 0.35, 4 at x = 0.7).
    layout "axis": one element from x = 0 to x = 1 (ends on the faces; line3 middle node 2).
    Returns beams and per element (x_start, x_end, columns of the coefficients, polynomials H_k).
    """
    if layout == "axis":
        X, conn, mids = {0: 0.0, 1: 1.0, 2: 0.5}, [(0, 1)], [2]
    else:
        X, conn, mids = {0: 0.2, 1: 0.9, 2: 0.5, 3: 0.35, 4: 0.7}, [(0, 2), (2, 1)], [3, 4]
    n_end_nodes = 2 if layout == "axis" else 3
    pt = lambda x: [x, 0.5, 0.5]  # noqa: E731
    if kind == "hermite":
        d = [1.0, 0.0, 0.0]
        beams = BeamMesh.hermite([pt(X[i]) for i in range(n_end_nodes)], [d] * n_end_nodes, conn)
        out = [(X[n1], X[n2], [2 * n1, 2 * n1 + 1, 2 * n2, 2 * n2 + 1], hermite_polys(X[n2] - X[n1]))
               for n1, n2 in conn]
        return beams, out
    if kind == "line":
        beams = BeamMesh.lagrange([pt(X[i]) for i in range(n_end_nodes)], conn, "line")
        H = [P([0.5, -0.5]), P([0.5, 0.5])]
        return beams, [(X[n1], X[n2], [n1, n2], H) for n1, n2 in conn]
    conn3 = [(n1, n2, m) for (n1, n2), m in zip(conn, mids)]
    beams = BeamMesh.lagrange([pt(X[i]) for i in range(len(X))], conn3, "line3")
    H = [P([0, -0.5, 0.5]), P([0, 0.5, 0.5]), P([1, 0, -1])]
    return beams, [(X[n1], X[n2], [n1, n2, m], H) for n1, n2, m in conn3]


def _expected_axis_operators(solid, kind, lm, layout):
    beams, elements = _axis_beams(kind, layout)
    n_beam_nodes = beams.n_nodes
    n_int = len(LM_NODES[lm]) - 2
    n_lm = n_beam_nodes + n_int * len(elements)
    per_node = 2 if kind == "hermite" else 1
    D = np.zeros((n_lm, per_node * n_beam_nodes))
    M = np.zeros((n_lm, solid.n_nodes))
    kappa = np.zeros(n_lm)
    Phi = lagrange_polys(LM_NODES[lm])
    for e, (x0, x1, cols, H) in enumerate(elements):
        jac = 0.5 * (x1 - x0)                               # |dr/dη| (straight, uniform)
        x_of_eta = P([0.5 * (x0 + x1), 0.5 * (x1 - x0)])
        # LM nodes: the beam element's end nodes, then its interior LM nodes (docs/conventions.md §2)
        lm_ids = [beams.elements[e, 0], beams.elements[e, 1]] + [n_beam_nodes + n_int * e + i
                                                                 for i in range(n_int)]
        for j, row in enumerate(lm_ids):
            kappa[row] += jac * integrate(Phi[j])
            for k, col in enumerate(cols):
                D[row, col] += jac * integrate(Phi[j] * H[k])
            # N_a on the line y = z = 1/2 of [0,1]^3: (x or 1-x) · 1/2 · 1/2, by the node's position
            for node, px in enumerate(solid.points[:, 0]):
                fx = x_of_eta if px == 1.0 else 1.0 - x_of_eta
                M[row, node] += jac * integrate(Phi[j] * fx * 0.25)
    return beams, D, M, kappa


@pytest.mark.parametrize("integration", ["segment", "element"])
@pytest.mark.parametrize("lm", ["line2", "line3", "line4"])
@pytest.mark.parametrize("kind", ["hermite", "line", "line3"])
@pytest.mark.parametrize("layout", ["pieces", "axis"])
def test_D_M_kappa_closed_form_on_hex_axis(layout, kind, lm, integration):
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams, D, M, kappa = _expected_axis_operators(solid, kind, lm, layout)
    ops = assemble_mortar(beams, solid, integration=integration, lm=lm)
    n_lm = len(kappa)
    assert ops.n_lm == n_lm
    assert ops.D.shape == (3 * n_lm, beams.n_centreline_dofs)
    assert ops.M.shape == (3 * n_lm, 3 * solid.n_nodes)
    assert beams.n_centreline_dofs == (6 if kind == "hermite" else 3) * beams.n_nodes
    I3 = np.eye(3)
    np.testing.assert_allclose(ops.D.toarray(), np.kron(D, I3), rtol=0, atol=1e-14)
    np.testing.assert_allclose(ops.M.toarray(), np.kron(M, I3), rtol=0, atol=1e-14)
    np.testing.assert_allclose(ops.kappa, kappa, rtol=0, atol=1e-14)
    length = 1.0 if layout == "axis" else 0.7
    assert ops.embedded_length == pytest.approx(length, rel=1e-14)
    assert ops.kappa.sum() == pytest.approx(length, rel=1e-14)
    # every LM node is coupled except the LM rows numbered after the middle beam nodes of line3
    # beams: they carry the beam node's index but no multiplier function
    unused = ([2] if layout == "axis" else [3, 4]) if kind == "line3" else []
    assert np.all(np.delete(ops.kappa, unused) > 0) and np.all(ops.kappa[unused] == 0)
    # the segments are the two whole beam elements in element 0
    if integration == "segment":
        assert_segments(ops, [(e, 0, -1.0, 1.0) for e in range(beams.n_elements)], tol=0.0)
    # the certificates: D q_B = M X_S exactly for the straight beam
    assert ops.constraint_residual < 1e-14
    np.testing.assert_allclose(ops.D @ beams.centreline_dofs(), ops.M @ solid.points.ravel(), atol=1e-15)


def test_hermite_D_spot_values():
    """A few entries of D written out by hand (line2, one element from x = 0 to 1, L = 1).

    Φ_0 = (1-η)/2, |r'| = L/2 = 1/2:
    H_1: ∫(1-η)(2-3η+η³)/8 = (4 + 2 - 2/5)/8 = 7/10      -> D = 7/20
    H_2: ∫(1-η)(1-η-η²+η³)/16 = (2 - 2/5)/16 = 1/10      -> D = 1/20
    H_3: ∫(1-η)(2+3η-η³)/8 = (4 - 2 + 2/5)/8 = 3/10      -> D = 3/20
    H_4: ∫(1-η)(-1-η+η²+η³)/16 = (-2 + 4/3 - 2/5)/16 = -1/15 -> D = -1/30
    """
    solid = generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1))
    beams = straight_beam((0.0, 0.5, 0.5), (1.0, 0.5, 0.5))
    ops = assemble_mortar(beams, solid)
    D = ops.D.toarray()
    assert D[0, 0] == pytest.approx(7 / 20, abs=1e-15)
    assert D[0, 3] == pytest.approx(1 / 20, abs=1e-15)
    assert D[1, 1] == pytest.approx(7 / 20, abs=1e-15) and D[1, 0] == 0.0
    assert D[0, 6] == pytest.approx(3 / 20, abs=1e-15)
    assert D[0, 9] == pytest.approx(-1 / 30, abs=1e-15)
    # κ = L/2 each; embedded length 1
    np.testing.assert_allclose(ops.kappa, [0.5, 0.5], atol=1e-15)


# --------------------------------------------------------------------------------------------
# C. element-based integration: ownership and dropped points
# --------------------------------------------------------------------------------------------
def test_element_based_ownership_and_dropped_points():
    """n_gauss = 5 on x(η) = 1 + 1.25 η: η = 0 lies exactly on the shared face x = 1 -> element 0;
    η = ±0.906 lie outside (x < 0 and x > 2) -> dropped."""
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    a, b = np.array([-0.25, 0.3, 0.2]), np.array([2.25, 0.6, 0.7])
    d = unit(b - a)
    beams = BeamMesh.hermite([a, b], [d, d], [[0, 1]])
    L = np.linalg.norm(b - a)
    gx, gw = np.polynomial.legendre.leggauss(5)
    x_g = 1.0 + 1.25 * gx
    ops = assemble_mortar(beams, solid, integration="element", n_gauss=5)
    assert ops.diagnostics["points_uncoupled"] == 2
    pts = ops.points
    assert len(pts) == 3
    np.testing.assert_allclose(pts["eta"], gx[1:4], atol=1e-15)
    assert list(pts["solid_element"]) == [0, 0, 1]
    assert abs(pts["position"][1, 0] - 1.0) < 1e-15
    np.testing.assert_allclose(pts["position"][:, 0], x_g[1:4], atol=1e-15)
    np.testing.assert_allclose(pts["weight"], gw[1:4] * L / 2, rtol=1e-14)
    assert ops.embedded_length == pytest.approx(gw[1:4].sum() * L / 2, rel=1e-14)
    assert ops.embedded_length < L * 0.8 * 0.99            # smaller than the inside length 0.8 L
    kappa = [sum(gw[g] * L / 2 * (1 - gx[g]) / 2 for g in (1, 2, 3)),
             sum(gw[g] * L / 2 * (1 + gx[g]) / 2 for g in (1, 2, 3))]
    np.testing.assert_allclose(ops.kappa, kappa, rtol=1e-14)
    # the element-based "segments": one row per group spanning its first and last point
    assert_segments(ops, [(0, 0, gx[1], gx[2]), (0, 1, gx[3], gx[3])], tol=1e-15)
    # M: Σ_g Φ_j N_a at the points; rebuild by hand (trilinear on unit cells)
    M = np.zeros((2, solid.n_nodes))
    for g, s in zip((1, 2, 3), (0, 0, 1)):
        p = a + (gx[g] + 1) / 2 * (b - a)
        lo = np.array([s, 0.0, 0.0])
        for node, X in enumerate(solid.points):
            if not (np.all(X >= lo) and np.all(X <= lo + 1)):
                continue
            N = np.prod([(p[i] - lo[i]) if X[i] == lo[i] + 1 else (lo[i] + 1 - p[i]) for i in range(3)])
            for j, phi in enumerate(((1 - gx[g]) / 2, (1 + gx[g]) / 2)):
                M[j, node] += gw[g] * L / 2 * phi * N
    np.testing.assert_allclose(ops.M.toarray(), np.kron(M, np.eye(3)), atol=1e-14)
    assert ops.constraint_residual < 1e-14


@pytest.mark.parametrize("name", list(DEGENERATE_BEAMS))
def test_element_based_points_go_to_lowest_index_element(name):
    solid = generate.box((0, 0, 0), (2, 2, 2), (2, 2, 2))
    a, b = DEGENERATE_BEAMS[name]
    beams = straight_beam(a, b)
    L = np.linalg.norm(np.subtract(b, a))
    ops = assemble_mortar(beams, solid, integration="element", n_gauss=7)
    pts = ops.points
    assert len(pts) == 7
    for p in pts:
        assert p["solid_element"] == min(cell_owners(p["position"], (0, 0, 0), 1.0, (2, 2, 2)))
    assert ops.embedded_length == pytest.approx(L, rel=1e-13)


def test_element_based_equals_segment_based_when_the_beam_lies_in_one_element():
    solid = generate.box((0, 0, 0), (2, 1, 1), (2, 1, 1))
    r1, r2 = np.array([1.1, 0.2, 0.3]), np.array([1.8, 0.8, 0.6])
    beams = BeamMesh.hermite([r1, r2], [unit([0.6, 0.7, 0.4]), unit([1.0, -0.5, 0.3])], [[0, 1]])
    seg = assemble_mortar(beams, solid, integration="segment", lm="line3")
    ele = assemble_mortar(beams, solid, integration="element", lm="line3")
    np.testing.assert_allclose(seg.D.toarray(), ele.D.toarray(), atol=1e-15)
    np.testing.assert_allclose(seg.M.toarray(), ele.M.toarray(), atol=1e-15)
    np.testing.assert_allclose(seg.kappa, ele.kappa, atol=1e-15)
