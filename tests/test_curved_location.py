"""Point location in curved quadratic elements, and the validity check that curved elements need.

A curved element's map extended beyond the element folds: a point inside can have a second
solution of x(ξ) = p outside the element, and Newton from the linearised map may converge to it.
Before this was handled, such a point counted as outside and a beam there was silently not
coupled (every consumer uses the same locator). The instances below were found by scanning random
mildly curved elements; each test first shows the trap (plain Newton converges outside) and then
that the library finds the point inside.
"""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d.elements.solid.dispatch import SOLID_ELEMENTS, SOLID_MODULES
from mortar1d3d.elements.validity import FOLDED, VALID, jacobian_validity
from mortar1d3d.geometry.projection import (CONVERGED, INSIDE, linear_maps, linear_parameters, project_point)
from mortar1d3d.geometry.search import solid_frames

import hard_cases as hc
from naive import outside_distance, reference_samples

# corners of the unit cube (VTK order); mid-side nodes moved by up to 5 % of the size: det J lies
# between 0.53 and 1.60 times that of the straight element
CURVED_HEX27 = np.array([
    [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
    [0.5218, -0.0281, -0.0432], [1.0155, 0.4601, -0.0445], [0.4548, 1.0227, -0.0456], [-0.0249, 0.4623, -0.0023],
    [0.4908, 0.0273, 0.9653], [0.9744, 0.5406, 0.9945], [0.4846, 0.9944, 0.961], [-0.0338, 0.5316, 0.9703],
    [-0.0212, -0.0287, 0.4701], [1.0339, -0.0114, 0.5461], [1.0432, 1.007, 0.5471], [-0.0215, 0.9661, 0.4649],
    [0.0404, 0.4804, 0.524], [0.997, 0.5158, 0.4626], [0.5369, 0.0487, 0.5407], [0.5175, 0.9657, 0.548],
    [0.5227, 0.4947, 0.0119], [0.4679, 0.5432, 0.9552], [0.539, 0.4811, 0.5411]])
# the unit corner tet with its mid-edge nodes moved by up to 8 % of the size
CURVED_TET10 = np.array([
    [0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.505, 0.0092, -0.0099], [0.432, 0.4279, -0.0037],
    [0.0744, 0.4494, 0.0726], [0.074, 0.0653, 0.5405], [0.4298, 0.0718, 0.5378], [0.0183, 0.4411, 0.4309]])
TRAPS = {"hexahedron27": (CURVED_HEX27, [-0.9968818899352554, 0.9996973454527656, -0.9999852596410316]),
         "tetra10": (CURVED_TET10, [0.004455838530925952, 0.9028133942671045, 0.02192874636130384])}


def single(name, X):
    return m13.SolidMesh(X, {name: np.arange(len(X))[None]})


def mapped(name, X, xi):
    N = np.empty(len(X))
    SOLID_MODULES[name].shape.py_func(np.asarray(xi, dtype=float), N)
    return N @ X


def plain_newton(solid, p):
    """ξ from Newton started at the element's linearised map, as the locator's first step does."""
    table = np.empty((1, 5, 3))
    _, h, origin = solid_frames(solid)
    linear_maps(solid.points, solid.connectivity, solid.element_codes, origin, h, table, 1)
    code = int(solid.element_codes[0])
    X = solid.points - origin[0]
    x = np.asarray(p, dtype=float) - origin[0]
    xi, trial = np.empty(3), np.empty(3)
    N, dN = np.empty(27), np.empty((27, 3))
    converged = (linear_parameters(code, table, 0, x[0], x[1], x[2], xi)
                 and project_point(code, X, x[0], x[1], x[2], h[0], xi, trial, N, dN) == CONVERGED)
    return xi, converged


@pytest.mark.parametrize("name", list(TRAPS))
def test_point_near_a_corner_of_a_curved_element_is_found_inside(name):
    X, xi_true = TRAPS[name]
    solid = single(name, X)
    assert jacobian_validity(SOLID_ELEMENTS[name], X[None], np.array([1.7]))[0] == VALID
    p = mapped(name, X, xi_true)
    xi_newton, converged = plain_newton(solid, p)
    assert converged and outside_distance(SOLID_ELEMENTS[name].family, xi_newton) > 0.01   # the trap
    xi, status = m13.project_points(solid, p[None], 0)
    assert status[0] == INSIDE
    np.testing.assert_allclose(xi[0], xi_true, rtol=0, atol=1e-10)


@pytest.mark.parametrize("integration", ["segment", "auto", "element"])
def test_beam_near_a_corner_of_a_curved_hex27_is_coupled(integration):
    """A straight beam inside the curved hex27 near its corner ξ = (-1, 1, -1), all of whose points
    lie in the trap region: it was not coupled at all (embedded length 0, no warning)."""
    a = mapped("hexahedron27", CURVED_HEX27, [-0.99, 0.96, -0.98])
    b = mapped("hexahedron27", CURVED_HEX27, [-0.96, 0.99, -0.96])
    solid = single("hexahedron27", CURVED_HEX27)
    for eta in np.linspace(0.0, 1.0, 5):
        assert plain_newton(solid, a + eta * (b - a))[1]                   # converges ...
        assert outside_distance("hex", plain_newton(solid, a + eta * (b - a))[0]) > 0   # ... outside
    beams = hc.straight(a, b, 2)
    assert hc.embedded_intervals(beams, solid, 0) == [(-1.0, 1.0, True)]   # independent: fully inside
    ops = m13.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
    assert ops.embedded_length == pytest.approx(np.linalg.norm(b - a), rel=1e-12)
    assert ops.diagnostics["points_outside_element"] == 0 and ops.diagnostics["points_not_converged"] == 0
    assert ops.constraint_residual < 1e-13


# det J > 0 at every node and at the centre (all the earlier check sampled) but negative inside:
# mid-side nodes, unit cube / unit corner tet corners
FOLDED_MIDS = {
    "hexahedron20": [[0.468, 0.128, -0.279], [0.934, 0.716, 0.048], [0.535, 1.099, 0.107], [0.05, 0.452, -0.19],
                     [0.376, -0.124, 0.958], [1.299, 0.412, 0.968], [0.423, 1.049, 1.269], [0.233, 0.426, 0.86],
                     [0.231, -0.004, 0.611], [0.744, 0.22, 0.388], [0.997, 0.819, 0.452], [0.197, 1.197, 0.484]],
    "hexahedron27": [[0.689, -0.053, 0.24], [1.041, 0.506, 0.152], [0.648, 0.748, 0.089], [-0.183, 0.343, -0.042],
                     [0.568, -0.001, 0.711], [0.87, 0.257, 0.78], [0.405, 1.0, 1.09], [0.279, 0.645, 1.042],
                     [-0.112, 0.181, 0.636], [1.191, 0.247, 0.431], [0.992, 1.262, 0.419], [-0.017, 0.986, 0.663],
                     [-0.242, 0.603, 0.352], [0.857, 0.437, 0.396], [0.791, 0.01, 0.315], [0.413, 1.1, 0.761],
                     [0.557, 0.304, 0.028], [0.445, 0.41, 0.986], [0.269, 0.619, 0.667]],
    "tetra10": [[0.422, -0.298, 0.198], [0.293, 0.361, 0.228], [0.006, 0.708, 0.084], [0.145, -0.245, 0.525],
                [0.505, 0.223, 0.417], [0.059, 0.236, 0.433]],
}
# where det J is negative (found by minimising det J; the value there)
FOLD_WITNESS = {"hexahedron20": ([-1.0, -1.0, 0.42855090770674004], -0.0077),
                "hexahedron27": ([-1.0, 0.2781827141552246, 0.7897089033312761], -0.062),
                "tetra10": ([0.0, 0.7991453333373847, 0.20085466666261584], -0.042)}


def folded(name):
    d = SOLID_ELEMENTS[name]
    corners = d.reference_nodes[:8] * 0.5 + 0.5 if d.family == "hex" else d.reference_nodes[:4]
    return np.vstack([corners, FOLDED_MIDS[name]])


def det_j(name, X, xi):
    from mortar1d3d.elements.validity import shape_gradients
    return float(np.linalg.det(X.T @ shape_gradients(SOLID_ELEMENTS[name], np.atleast_2d(xi))[0]))


@pytest.mark.parametrize("name", list(FOLDED_MIDS))
def test_element_folded_between_sample_points_is_rejected(name):
    d = SOLID_ELEMENTS[name]
    X = folded(name)
    samples = np.vstack([d.reference_nodes, d.centre[None]])
    assert min(det_j(name, X, xi) for xi in samples) > 1e-3               # what the nodes and centre say
    witness, value = FOLD_WITNESS[name]
    assert det_j(name, X, witness) == pytest.approx(value, abs=5e-4)       # a fold inside
    assert jacobian_validity(d, X[None], np.array([1.7]))[0] == FOLDED
    straight = (d.reference_nodes * 0.5 + 0.5 if d.family == "hex" else d.reference_nodes) + 5.0
    points = np.vstack([straight, X])                                       # a valid element first
    cells = np.vstack([np.arange(len(X)), np.arange(len(X), 2 * len(X))])
    with pytest.raises(m13.MeshError, match=rf"^folded {name} elements .*: 1$"):
        m13.SolidMesh(points, {name: cells})


def test_wedge_folded_between_its_nodes_is_rejected():
    """A wedge6 has no mid-side nodes but is not affine: det J is quadratic in ζ along its vertical edges
    (here positive at the six nodes and the centre, negative on the edge between nodes 2 and 5)."""
    d = SOLID_ELEMENTS["wedge"]
    X = np.array([[0.283, 0.277, -0.14], [1.019, 0.403, -0.123], [-0.281, 0.554, 0.401],
                  [-0.447, 0.446, 0.638], [1.344, -0.325, 1.226], [0.433, 0.86, 1.227]])
    samples = np.vstack([d.reference_nodes, d.centre[None]])
    assert min(det_j("wedge", X, xi) for xi in samples) > 0.04
    assert det_j("wedge", X, [0.0, 1.0, -0.2708]) == pytest.approx(-0.0152, abs=1e-4)
    assert jacobian_validity(d, X[None], np.array([1.7]))[0] == FOLDED
    with pytest.raises(m13.MeshError, match=r"^folded wedge elements .*: 0$"):
        m13.SolidMesh(X, {"wedge": np.arange(6)[None]})


@pytest.mark.parametrize("name", [n for n, d in SOLID_ELEMENTS.items() if not d.rational])
def test_validity_bound_agrees_with_dense_sampling(name):
    """Random perturbations of every node (and of the mid-side nodes far beyond validity): every element
    the Bernstein bound accepts has det J > 0 at 11³ sample points, and every element with a non-positive
    sample is rejected. (The bound may reject elements whose fold lies between the samples: the ones
    above.)"""
    from mortar1d3d.elements.validity import shape_gradients
    d = SOLID_ELEMENTS[name]
    rng = np.random.default_rng(4)
    X = np.tile(d.reference_nodes, (400, 1, 1)).astype(float)
    X += 0.1 * rng.uniform(-1, 1, X.shape)
    n_corners = len(d.family_type.corners)
    X[:, n_corners:] += 0.3 * rng.uniform(-1, 1, X[:, n_corners:].shape)
    outcome = jacobian_validity(d, X, np.full(len(X), 3.0))
    pts = reference_samples(d.family, 11)
    det = np.linalg.det(np.einsum("mai,saj->msij", X, shape_gradients(d, pts)))
    bad = (det <= 0).any(axis=1)
    assert not np.any(bad & (outcome == VALID))
    assert np.all(outcome[bad] != VALID)
    if d.degree == 2:
        assert bad.any() and (~bad).any()           # both kinds are exercised


@pytest.mark.parametrize("name", ["hexahedron", "hexahedron27", "tetra10"])
def test_certificates_computed_on_first_use_give_the_margins_computed_beforehand(name):
    """``linear_maps`` leaves every curved element's one-to-one certificate pending; the first ξ within
    the largest certified box makes ``certified_outside`` compute it: the margin ``certified_margin``
    gives, stored, and every answer (before and after it is stored) the one that margin gives. A ξ
    beyond that box is answered without computing it."""
    from mortar1d3d.elements.solid.dispatch import CENTRE, MAX_NODES, RADIUS
    from mortar1d3d.geometry.projection import (PENDING_CERTIFICATE, certified_margin, certified_outside,
                                                load_element, search_buffers)
    solid = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (3, 3, 3), name), 0.2, seed=2)
    _, h, origin = solid_frames(solid)
    table = np.empty((solid.n_elements, 5, 3))
    linear_maps(solid.kernel_points, solid.connectivity, solid.element_codes, origin, h, table, 1)
    curved = np.flatnonzero(table[:, 4, 0] == 0.0)
    assert len(curved) == solid.n_elements and (table[curved, 4, 1] == PENDING_CERTIFICATE).all()
    X = np.empty((MAX_NODES, 4))
    a, _ = search_buffers()
    rng = np.random.default_rng(5)
    margins = []
    for s in curved:
        code = int(solid.element_codes[s])
        load_element(solid.kernel_points, solid.connectivity, s, code, origin, X)
        eager = certified_margin(code, X, table[s, :3].copy(), a)
        margins.append(eager)
        centre, radius = CENTRE[code], RADIUS[code]
        beyond = centre + (radius + 1.0) * 1.01 * rng.choice([-1.0, 1.0], 3)
        assert not certified_outside(code, table, s, beyond, X, a)
        assert table[s, 4, 1] == PENDING_CERTIFICATE                  # nothing computed for it
        for xi in centre + (radius + 1.0) * rng.uniform(-1.0, 1.0, (30, 3)):
            reach = np.abs(xi - centre).max() - radius
            assert certified_outside(code, table, s, xi, X, a) == (eager >= 0.0 and reach <= eager)
            assert table[s, 4, 1] == eager
    assert len(set(margins)) > 1            # elements with different margins (or none) are exercised
