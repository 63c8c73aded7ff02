"""The engine on NURBS solids (issue 19 item 3): quadratic NURBS spans as rational Bézier elements
(``nurbs27``) in point location, segmentation, integration, assembly and the certificates.

References: the exact hollow-cylinder sector (a point's radius, angle and height) with crossings by
bisection (tests/naive.py), and the NURBS functions by Cox–de Boor over the knot vectors.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import nurbs
from mortar1d3d.elements.validity import FOLDED, INVERTED, VALID, jacobian_validity
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS
from mortar1d3d.geometry.projection import INSIDE, OUTSIDE

import naive

NURBS27 = SOLID_ELEMENTS["nurbs27"]


def sector(angle=90.0, elements=(1, 1, 1), r=(0.1, 0.2), height=0.3, degree=2):
    return nurbs.bezier_mesh(nurbs.hollow_cylinder(r[0], r[1], height, angle=angle, elements=elements, degree=degree))


def jittered(seed):
    """A closed pipe with control points moved by up to 2 % of the wall and weights scaled by 0.8…1.25:
    genuinely rational, curved elements of unequal weights (still valid)."""
    rng = np.random.default_rng(seed)
    patch = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=360.0, elements=(2, 4, 2)).patches[0]
    control = patch.control + rng.uniform(-0.002, 0.002, patch.control.shape)
    control[:, -1] = control[:, 0]                   # keep the seam closed
    weights = patch.weights * rng.uniform(0.8, 1.25, patch.weights.shape)
    weights[:, -1] = weights[:, 0]
    return nurbs.bezier_mesh(nurbs.NurbsSolid([nurbs.NurbsPatch(control, weights, patch.knots, patch.degrees)]))


@pytest.mark.parametrize("mesh", ["sector90", "pipe120", "jittered", "pipe120_cubic", "pipe120_quartic"])
def test_points_are_found_where_they_are(mesh):
    """The trust property on NURBS spans: x(ξ) for random ξ inside is INSIDE at ξ to 1e-10, and
    x(ξ) just beyond a face (1e-6 in ξ) is never INSIDE (OUTSIDE at that ξ, or no solution found:
    NOT_CONVERGED, after the search proved that none lies inside)."""
    bm = {"sector90": lambda: sector(), "pipe120": lambda: sector(360.0, (1, 3, 1), r=(0.2, 0.3), height=1.0),
          "jittered": lambda: jittered(3),
          "pipe120_cubic": lambda: sector(360.0, (1, 3, 1), r=(0.2, 0.3), height=1.0, degree=3),
          "pipe120_quartic": lambda: sector(360.0, (1, 3, 1), r=(0.2, 0.3), height=1.0, degree=4)}[mesh]()
    rng = np.random.default_rng(11)
    patch = bm.nurbs.patches[0]
    xi = rng.uniform(-1, 1, (60, 3))
    x = patch.evaluate_elements(xi)
    elements = np.repeat(np.arange(patch.n_elements), len(xi))
    found, status = m13.project_points(bm.solid, x.reshape(-1, 3), elements)
    assert (status == INSIDE).all()
    assert np.abs(found - np.tile(xi, (patch.n_elements, 1))).max() < 1e-10
    out = xi.copy()
    axis = rng.integers(0, 3, len(out))
    out[np.arange(len(out)), axis] = np.where(rng.uniform(size=len(out)) < 0.5, -1.0, 1.0) * (1 + 1e-6)
    x = patch.evaluate_elements(out)
    found, status = m13.project_points(bm.solid, x.reshape(-1, 3), elements)
    # outside: proved (OUTSIDE with the solution beyond the face) or no solution found at all
    assert not (status == INSIDE).any()
    hit = status == OUTSIDE
    assert hit.mean() > 0.95
    assert (np.abs(found[hit]).max(axis=1) > 1 + 1e-7).all()
    # mostly the solution beyond the face; a strongly rational element may have another one farther out
    assert (np.abs(found[hit] - np.tile(out, (patch.n_elements, 1))[hit]).max(axis=1) < 1e-10).mean() > 0.95


def _crossing_beam(points):
    """One Hermite element through a quadratic curve (reproduced exactly by the cubic)."""
    a, m, b = (np.asarray(p, dtype=float) for p in points)
    f = lambda t: (1 - t) ** 2 * a + 2 * t * (1 - t) * m + t * t * b
    df = lambda t: 2 * (1 - t) * (m - a) + 2 * t * (b - m)
    return m13.BeamMesh.from_curve(f, df, 0.0, 1.0, 1)


@pytest.mark.parametrize("degree", [2, 3, 4])
def test_curved_beam_crossing_the_inner_face_twice_has_two_pieces(degree):
    """A curved Hermite line through the 90° hollow-cylinder element (radii 0.1 / 0.2, height 0.3; one
    quadratic or, degree-elevated, cubic or quartic span): it enters through θ = 0, dips into the hole (the
    curved inner face, twice) and leaves through θ = 90°. Two pieces, at the crossings found by
    bisection of the exact sector."""
    bm = sector(degree=degree)
    beams = _crossing_beam([[0.16, -0.02, 0.05], [0.06, 0.06, 0.2], [-0.02, 0.16, 0.1]])
    reference = naive.indicator_crossings(lambda eta: beams.evaluate(0, eta),
                                          lambda x: naive.in_sector(x, 0.1, 0.2, 90.0, 0.3))
    assert len(reference) == 4
    ops = m13.assemble_mortar(beams, bm.solid, integration="segment", n_gauss=6)
    seg = np.sort(ops.segments, order="eta_start")
    assert len(seg) == 2 and (seg["solid_element"] == 0).all()
    found = np.column_stack([seg["eta_start"], seg["eta_end"]]).ravel()
    assert np.abs(found - reference).max() < 1e-12
    assert ops.constraint_residual < 1e-14
    length = naive.arc_length(beams, 0, reference[0], reference[1]) + naive.arc_length(beams, 0, reference[2],
                                                                                         reference[3])
    assert abs(ops.embedded_length - length) < 1e-9 * length     # 6 Gauss points on |r'| (not a polynomial)


@pytest.mark.parametrize("degree", [2, 3, 4])
@pytest.mark.parametrize("integration", ["segment", "element", "auto"])
def test_operators_on_a_closed_pipe(integration, degree):
    """Curved beams through a closed pipe of 2 × 6 × 2 elements (quadratic, cubic or quartic spans): the
    certificates hold, the segments tile the beam inside the pipe (coupled length = the length
    inside, by bisection), and M on the control points equals Σ w Φ_j R_i with R_i by Cox–de Boor."""
    bm = nurbs.bezier_mesh(nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=360.0, elements=(2, 6, 2), degree=degree))
    beams = m13.BeamMesh.join([_crossing_beam([[0.35, -0.05, 0.1], [0.0, 0.45, 0.5], [-0.35, 0.05, 0.9]]),
                               _crossing_beam([[0.28, -0.2, 0.3], [0.1, 0.1, 0.6], [-0.28, 0.2, 0.45]])])
    ops = m13.assemble_mortar(beams, bm.solid, integration=integration, n_gauss=6)
    assert ops.constraint_residual < 1e-13
    M = bm.nodes_to_control(ops.M)
    Dq = ops.D @ beams.centreline_dofs()
    assert np.linalg.norm(Dq - M @ bm.nurbs.control.ravel()) < 1e-13 * np.linalg.norm(Dq)
    patch = bm.nurbs.patches[0]
    ids = bm.nurbs.patch_ids[0]
    lm_rows, _ = naive.lm_rows(beams, 2)
    expected = np.zeros((ops.n_lm, bm.nurbs.n_control))
    for p in ops.points:
        R = naive.nurbs_functions(patch, int(p["solid_element"]), p["xi"])
        Phi = naive.multiplier_values("line2", p["eta"])
        rows = lm_rows[int(p["beam_element"])]
        np.add.at(expected, (rows[:, None], ids[None, :]), p["weight"] * np.outer(Phi, R))
    assert np.abs(M.toarray()[0::3, 0::3] - expected).max() < 1e-14
    if integration != "element":
        # the segments of each beam element, joined where they meet, are the parts inside the pipe
        for e in range(beams.n_elements):
            eta = naive.indicator_crossings(lambda t: beams.evaluate(e, t),
                                            lambda x: naive.in_sector(x, 0.2, 0.3, 360.0, 1.0))
            bounds = np.concatenate([[-1.0], eta, [1.0]])
            start_inside = naive.in_sector(beams.evaluate(e, [-1.0]), 0.2, 0.3, 360.0, 1.0)[0]
            expected = bounds[(0 if start_inside else 1):][: 2 * ((len(bounds) - (0 if start_inside else 1)) // 2)]
            seg = np.sort(ops.segments[ops.segments["beam_element"] == e], order="eta_start")
            joined = [seg["eta_start"][0]]
            for a, b in zip(seg["eta_end"][:-1], seg["eta_start"][1:]):
                if b - a > 1e-12:
                    joined += [a, b]
            joined.append(seg["eta_end"][-1])
            assert len(joined) == len(expected) and np.abs(np.array(joined) - expected).max() < 1e-12
            assert len(seg) > len(expected) // 2          # cut at the element faces inside the wall too


def test_validity_of_rational_elements():
    bm = jittered(5)
    X = bm.solid.points[bm.solid.connectivity[:, :27]]
    W = bm.solid.weights[bm.solid.connectivity[:, :27]]
    h = np.linalg.norm(X.max(axis=1) - X.min(axis=1), axis=1)
    assert (jacobian_validity(NURBS27, X, h, W) == VALID).all()
    # mirrored: inverted at the corners
    assert (jacobian_validity(NURBS27, X * [1, 1, -1], h, W) == INVERTED).all()
    # the centre control point of one element pushed through a face: folded inside, fine at the corners
    Y = X[:1].copy()
    Y[0, 26] = Y[0, 20] + 3.0 * (Y[0, 20] - Y[0, 21])
    assert jacobian_validity(NURBS27, Y, h[:1], W[:1])[0] == FOLDED
    with pytest.raises(m13.MeshError, match="weights"):
        m13.SolidMesh(bm.solid.points, {"nurbs27": bm.solid.connectivity[:, :27]})


def test_nurbs27_newton_kernels_equal_the_general_rational_path_to_round_off():
    """The map and Jacobian the Newton path uses on a nurbs27 (``projection.map_point`` / ``jacobian``:
    the type's homogeneous tensor contractions ``nurbs27.map_nodes`` / ``jacobian_nodes``) equal the
    general path to round-off: the registry's Bernstein shape functions and derivatives, the rational
    quotient of ``dispatch.rational_shape`` / ``rational_deriv`` and the sums over the nodes. Random
    control points and weights (0.3 to 3), ξ inside, on and beyond the reference cube."""
    from mortar1d3d.elements.solid import dispatch
    from mortar1d3d.geometry import projection as pr

    code = NURBS27.code
    rng = np.random.default_rng(11)
    X, N, dN, _, _, _, _ = pr.point_buffers()
    N_ref, dN_ref = np.empty_like(N), np.empty_like(dN)
    differ = exact = 0
    worst_x = worst_J = 0.0
    for _ in range(20):
        X[:27, :3] = NURBS27.reference_nodes + rng.uniform(-0.3, 0.3, (27, 3))
        X[:27, 3] = rng.uniform(0.3, 3.0, 27)
        for xi in np.concatenate([rng.uniform(-1.3, 1.3, (10, 3)), [[-1.0, 1.0, 0.0], [1.0, 1.0, 1.0]]]):
            x = np.array(pr.map_point(code, X, xi, N))
            dispatch.rational_shape(code, xi, X, N_ref)
            ref = N_ref[:27] @ X[:27, :3]
            worst_x = max(worst_x, np.abs(x - ref).max() / np.abs(ref).max())
            exact += np.array_equal(x, ref)
            J = np.array(pr.jacobian(code, X, xi, N, dN)).reshape(3, 3)
            dispatch.rational_deriv(code, xi, X, N_ref, dN_ref)
            J_ref = X[:27, :3].T @ dN_ref[:27]
            worst_J = max(worst_J, np.abs(J - J_ref).max() / np.abs(J_ref).max())
            # the weights matter (the comparison is not that of the polynomial map Σ B_a X_a)
            dispatch.shape(code, xi, N_ref)
            differ += not np.allclose(x, N_ref[:27] @ X[:27, :3], rtol=1e-6, atol=0.0)
    assert worst_x < 4e-15 and worst_J < 1e-13, (worst_x, worst_J)
    assert exact < 240          # another association of the sums: not the same bits everywhere
    assert differ >= 200        # every random ξ (at a corner, and here on an edge, R_a = B_a)


def test_nurbs27_newton_kernels_on_the_exact_cylinder():
    """On one span of an exact hollow-cylinder sector (90°, radii 0.1 / 0.2, height 0.3) the Newton
    path's map puts every ξ at radius 0.1 + 0.05 (ξ_0 + 1) and height 0.15 (ξ_2 + 1), and its Jacobian
    has the closed-form columns: ∂x/∂ξ_0 = 0.05 e_r, ∂x/∂ξ_2 = 0.15 e_z, ∂x/∂ξ_1 along e_θ (orthogonal
    to e_r and e_z), counter-clockwise."""
    from mortar1d3d.geometry import projection as pr

    solid = sector().solid
    X, N, dN, _, _, _, _ = pr.point_buffers()
    X[:27] = solid.kernel_points[solid.cells["nurbs27"][0]]
    rng = np.random.default_rng(5)
    for xi in np.concatenate([rng.uniform(-1.0, 1.0, (50, 3)), [[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]]):
        x = np.array(pr.map_point(NURBS27.code, X, xi, N))
        r = np.hypot(x[0], x[1])
        e_r = np.array([x[0], x[1], 0.0]) / r
        assert abs(r - (0.1 + 0.05 * (xi[0] + 1.0))) < 1e-15
        assert abs(x[2] - 0.15 * (xi[2] + 1.0)) < 1e-15
        assert x[0] >= -1e-15 and x[1] >= -1e-15         # in the first quadrant
        J = np.array(pr.jacobian(NURBS27.code, X, xi, N, dN)).reshape(3, 3)
        np.testing.assert_allclose(J[:, 0], 0.05 * e_r, rtol=0.0, atol=1e-15)
        np.testing.assert_allclose(J[:, 2], [0.0, 0.0, 0.15], rtol=0.0, atol=1e-15)
        assert abs(J[:, 1] @ e_r) < 1e-15 and abs(J[2, 1]) < 1e-15
        # counter-clockwise, r π/4 per unit ξ_1 on average over the span (the rational parametrisation's
        # speed varies about it)
        assert 0.5 * r * np.pi / 4 < np.cross(e_r, J[:, 1])[2] < 2.0 * r * np.pi / 4


@pytest.mark.parametrize("degree", [2, 3, 4])
@pytest.mark.parametrize("jitter", [0.0, 0.2])
def test_certificate_bound_about_the_centre_summed_by_degree(degree, jitter):
    """The one-to-one certificate of a rational element (``projection.certified_margin``) bounds the
    curvature about the element centre from the monomial sums per degree
    (``rational.centre_curvature_bound``): the bound of ``rational_curvature_bound`` at m = ξ_c with
    its terms summed by degree, equal to round-off, for radii from inside the element to beyond every
    margin tried, on the spans of an exact pipe (24 around: certified, margins 0.5 and 1) and of the
    same pipe with weights scaled by 0.8-1.25 (genuinely rational: no margin certified); and every
    element gets the margin the general bound gives."""
    from mortar1d3d.elements.solid import dispatch
    from mortar1d3d.geometry import projection as pr
    from mortar1d3d.geometry import rational as ra
    from mortar1d3d.geometry.search import solid_frames

    rng = np.random.default_rng(degree)
    patch = nurbs.hollow_cylinder(0.2, 0.3, 1.0, angle=360.0, elements=(2, 24, 2), degree=degree).patches[0]
    weights = patch.weights * rng.uniform(1.0 - jitter, 1.0 + 1.25 * jitter, patch.weights.shape)
    weights[:, -1] = weights[:, 0]
    mesh = nurbs.bezier_mesh(nurbs.NurbsSolid([nurbs.NurbsPatch(patch.control, weights, patch.knots,
                                                                patch.degrees)])).solid
    points, conn, codes = mesh.kernel_points, mesh.connectivity, mesh.element_codes
    _, h, origin = solid_frames(mesh)
    table = np.empty((mesh.n_elements, 5, 3))
    pr.linear_maps(points, conn, codes, origin, h, table, 1)
    X, a = np.empty((dispatch.MAX_NODES, 4)), np.empty((dispatch.MAX_NODES, 4))
    worst, margins = 0.0, []

    def difference(sums, code, r):
        K = ra.rational_curvature_bound(code, a, *dispatch.CENTRE[code], r)
        by_degree = ra.centre_curvature_bound(sums, r)
        assert np.isfinite(K) == np.isfinite(by_degree)      # W bounded away from zero in both or neither
        return K, abs(by_degree - K) / K if np.isfinite(K) else 0.0

    for s in range(mesh.n_elements):
        code = codes[s]
        pr.load_element(points, conn, s, code, origin, X)
        ra.rational_coefficients(code, X, a)
        ra.normalise_coefficients(code, a, table[s, :3].copy(), *ra.centre_point(code, a), a)
        sums = ra.degree_sums(code, a)
        general = -1.0
        for delta in (1.0, 0.5, 0.25, 0.125):
            reach = dispatch.RADIUS[code] + delta
            K, d = difference(sums, code, reach)
            worst = max(worst, d)
            if general < 0.0 and K * reach < 1.0:
                general = delta
        margins.append(general)
        for r in (0.1, 0.5, 3.0):
            worst = max(worst, difference(sums, code, r)[1])
    assert worst < 1e-12, worst      # round-off of the sums, grown by the cancellation in W_min = c_0 - B0
    # linear_maps leaves every certificate to its first use; the margin computed then is the general one
    assert np.all(table[:, 4, 1] == pr.PENDING_CERTIFICATE)
    scratch = np.empty((dispatch.MAX_NODES, 4))
    computed = []
    for s in range(mesh.n_elements):
        pr.load_element(points, conn, s, codes[s], origin, X)
        computed.append(pr.certified_margin(codes[s], X, table[s, :3].copy(), scratch))
    np.testing.assert_array_equal(computed, margins)
    assert sorted(set(margins)) == ([-1.0] if jitter else [0.5, 1.0])


@pytest.mark.parametrize("degree", [2, 3, 4])
@pytest.mark.parametrize("jitter", [0.0, 0.2])
def test_linearised_map_error_bound_of_rational_elements(degree, jitter):
    """The segmentation's bound of the linearised map on rational elements (``segmentation._linear_error``,
    :func:`mortar1d3d.geometry.rational.linearisation_error`): for random ξ in the element grown by the
    reach margin (inside, on its faces and corners, and up to the margin beyond), the linearised parameters
    ζ = ξ_c + L (x(ξ) - x_c) lie within ε_i of ξ_i, on the spans of a pipe (six around, 60° each) with control
    points moved by up to 4 % of the wall and weights scaled by 1 - jitter … 1 + 1.25 jitter: genuinely
    rational, curved elements. The bound is finite and not far above what the samples reach (a factor
    below 6; these spans are strongly curved: ζ - ξ reaches about 1 across the wall)."""
    from mortar1d3d.elements.solid import dispatch
    from mortar1d3d.geometry import projection as pr
    from mortar1d3d.geometry import segmentation
    from mortar1d3d.geometry.search import solid_frames

    rng = np.random.default_rng(10 * degree + int(10 * jitter))
    patch = nurbs.hollow_cylinder(0.1, 0.2, 0.3, angle=360.0, elements=(2, 6, 2), degree=degree).patches[0]
    control = patch.control + rng.uniform(-0.004, 0.004, patch.control.shape)
    control[:, -1] = control[:, 0]                   # keep the seam closed
    weights = patch.weights * rng.uniform(1.0 - jitter, 1.0 + 1.25 * jitter, patch.weights.shape)
    weights[:, -1] = weights[:, 0]
    mesh = nurbs.bezier_mesh(nurbs.NurbsSolid([nurbs.NurbsPatch(control, weights, patch.knots,
                                                                patch.degrees)])).solid
    points, conn, codes = mesh.kernel_points, mesh.connectivity, mesh.element_codes
    _, h, origin = solid_frames(mesh)
    table = np.empty((mesh.n_elements, 5, 3))
    pr.linear_maps(points, conn, codes, origin, h, table, 1)
    assert np.all(table[:, 4, 0] == 0.0)             # curved: every element has a linearisation, none affine
    errors = np.full((mesh.n_elements, 3), np.nan)
    segmentation._linear_errors(np.arange(mesh.n_elements), codes, conn, points, origin, table, errors)
    assert np.all(np.isfinite(errors)) and np.all(errors > 0.0)
    X, N, _, _, _, _, _ = pr.point_buffers()
    grown = 1.0 + segmentation._REACH_MARGIN
    ratios = []
    for s in range(mesh.n_elements):
        code = codes[s]
        pr.load_element(points, conn, s, code, origin, X)
        xi = rng.uniform(-grown, grown, (400, 3))
        xi[:100, 0] = rng.choice([-grown, grown], 100)                   # on the grown box's faces
        xi[100:150] = rng.choice([-grown, grown], (50, 3))               # and its corners
        zeta = np.array([pr.linear_image(code, table, s, *pr.map_point(code, X, p, N)) for p in xi])
        deviation = np.abs(zeta - xi).max(axis=0)
        assert np.all(deviation <= errors[s]), (s, deviation, errors[s])
        ratios.append(errors[s].max() / deviation.max())
    # the bound's largest component over the samples' largest deviation (largest on jittered weights, degree 4)
    assert max(ratios) < 6.0, max(ratios)
