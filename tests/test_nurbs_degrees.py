"""Patches of any degree 1 … 4 per direction (issue 19 item 1): exact degree elevation to the common
degree of the element registry (2: nurbs27, 3: nurbs64, 4: nurbs125), per direction and across patches;
the geometry (points and weights) is unchanged; a degree above 4 is an error saying what is supported."""
import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import nurbs
from mortar1d3d.nurbs import knots as kv
from mortar1d3d.nurbs.mesh import common_degree, element_values
from mortar1d3d.nurbs.patch import NurbsPatch, NurbsSolid
from mortar1d3d.nurbs.scene import patches_mesh, validate_patches
from mortar1d3d.nurbs.solid import NurbsSolidModel
from mortar1d3d.physics.materials import material
from mortar1d3d.physics.rational_surface import polynomial_values

RI, RO, L = 0.1, 0.2, 0.3


def test_bernstein_elevation_is_exact():
    x = np.linspace(-1.0, 1.0, 7)
    for p in (1, 2, 3):
        for q in range(p, 5):
            M = kv.bernstein_elevation(p, q)
            assert np.abs(kv.bernstein_values(p, x) - kv.bernstein_values(q, x) @ M.T).max() < 1e-15
    with pytest.raises(ValueError, match="must not be lower"):
        kv.bernstein_elevation(3, 2)


def wavy_patch(degrees, seed=0):
    """A patch of the given degrees with two spans per direction, perturbed control points and weights
    (a general rational volume, not a pipe)."""
    rng = np.random.default_rng(seed)
    U = [np.concatenate([[0.0] * (p + 1), [0.4], [1.0] * (p + 1)]) for p in degrees]
    shape = tuple(p + 2 for p in degrees)
    grid = np.stack(np.meshgrid(*[np.linspace(0.0, 1.0, n) for n in shape], indexing="ij"), axis=-1)
    control = grid * [1.0, 0.7, 0.5] + 0.03 * rng.standard_normal(grid.shape)
    weights = rng.uniform(0.6, 1.4, shape)
    return NurbsPatch(control, weights, tuple(U), degrees)


@pytest.mark.parametrize("degrees, element", [((1, 1, 1), "nurbs27"), ((1, 2, 1), "nurbs27"),
                                              ((2, 1, 2), "nurbs27"), ((1, 3, 2), "nurbs64"),
                                              ((3, 1, 1), "nurbs64"), ((3, 3, 3), "nurbs64"),
                                              ((4, 1, 2), "nurbs125"), ((2, 4, 3), "nurbs125")])
def test_mixed_degrees_keep_the_geometry(degrees, element):
    patch = wavy_patch(degrees)
    mesh = nurbs.bezier_mesh(NurbsSolid([patch]))
    solid = mesh.solid
    assert solid.blocks[0][0].name == element and solid.n_elements == 8
    # points of the elements (rational Bézier kernel, elevated) = the patch's own (Cox–de Boor, unelevated)
    rng = np.random.default_rng(1)
    xi = rng.uniform(-1.0, 1.0, (6, 3))
    x = element_values(solid, xi, solid.points)                                 # (8, 6, 3)
    lo, hi = patch.element_ranges()[:, :, 0], patch.element_ranges()[:, :, 1]
    u = lo[:, None, :] + 0.5 * (xi[None] + 1.0) * (hi - lo)[:, None, :]
    assert np.abs(x - patch.evaluate(u.reshape(-1, 3)).reshape(x.shape)).max() < 1e-14
    # the weight function too: W = Σ_a w_a B_a of the elevated elements = Σ_i w_i N_i of the patch
    d, conn = solid.blocks[0]
    B, _ = polynomial_values(d.code, xi, d.n_nodes)
    W = np.einsum("qa,ea->eq", B, solid.weights[conn])
    N = [kv.bspline_values(U, q, u.reshape(-1, 3)[:, k]) for k, (U, q) in enumerate(zip(patch.knots, patch.degrees))]
    W_patch = np.einsum("mi,mj,mk,ijk->m", *N, patch.weights).reshape(W.shape)
    assert np.abs(W - W_patch).max() < 1e-14
    # nodes and weights = those of the patch degree-elevated globally (knot vectors and control net)
    p = common_degree(degrees)
    global_ = patch.elevate(0, p - degrees[0]).elevate(1, p - degrees[1]).elevate(2, p - degrees[2])
    ref = nurbs.bezier_mesh(NurbsSolid([global_])).solid
    assert ref.n_nodes == solid.n_nodes
    assert np.abs(ref.points - solid.points).max() < 1e-14
    assert np.abs(ref.weights - solid.weights).max() < 1e-14
    # T maps the patch's own control points (its space, not the elevated one's) onto the nodes
    assert mesh.T.shape == (solid.n_nodes, patch.n_control)
    assert np.abs(mesh.T @ NurbsSolid([patch]).control - solid.points).max() < 1e-14
    assert np.abs(np.asarray(mesh.T.sum(axis=1)).ravel() - 1.0).max() < 1e-14


def test_a_linear_brick_on_quadratic_elements_passes_the_patch_test():
    """Uniaxial stress u = ε (x, −ν y, −ν z) on a degree-1 brick of 2 × 1 × 1 spans (nurbs27 elements,
    12 control points): the forces on the control points are σ A / 4 on each x = 2 corner, − that on
    each x = 0 corner and zero at x = 1."""
    E, nu, eps = 10.0, 0.3, 1e-3
    solid = nurbs.brick([0, 0, 0], [2, 1, 1], elements=(2, 1, 1), degree=1)
    model = NurbsSolidModel(solid, material("linear_elastic", E, nu), kinematics="linear")
    assert model.n_dofs == 3 * 12 and model.mesh.solid.blocks[0][0].name == "nurbs27"
    X = solid.control
    u = eps * X * [1.0, -nu, -nu]
    f, _ = model.evaluate(u.ravel(), tangent=False)
    f = f.reshape(-1, 3)
    expected = np.zeros_like(f)
    expected[np.isclose(X[:, 0], 2.0), 0] = E * eps / 4
    expected[np.isclose(X[:, 0], 0.0), 0] = -E * eps / 4
    assert np.abs(f - expected).max() < 1e-12 * E * eps


def test_patches_of_other_degrees_join_in_a_scene():
    """Three 120° pipe sections of degrees [1, 2, 1], 2 and [2, 3, 1]: elevated to the common degree 3 before
    joining, so they are the closed cubic pipe (same nodes, same weights)."""
    sections = [{"pipe": {"r_inner": RI, "r_outer": RO, "length": L, "elements": [1, 1, 1], "angle": 120.0,
                          "start": 120.0 * k, "degree": degree}} for k, degree in enumerate([[1, 2, 1], 2, [2, 3, 1]])]
    mesh, bm = patches_mesh(validate_patches(sections))
    one, _ = patches_mesh(validate_patches([{"pipe": {"r_inner": RI, "r_outer": RO, "length": L,
                                                       "elements": [1, 3, 1], "degree": 3}}]))
    assert mesh.blocks[0][0].name == "nurbs64" and mesh.n_nodes == one.n_nodes == 4 * 9 * 4
    key = lambda m: np.lexsort(np.round(np.column_stack([m.points, m.weights]), 12).T)       # noqa: E731
    a, b = key(mesh), key(one)
    assert np.abs(mesh.points[a] - one.points[b]).max() < 1e-14
    assert np.abs(mesh.weights[a] - one.weights[b]).max() < 1e-14
    assert "cut_start" not in mesh.point_sets and len(mesh.point_sets["inner"]) == 9 * 4
    m13.plan(m13.Scene(solid={"mesh": {"patches": sections},
                              "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                       dirichlet=[{"on": "solid:start", "components": ["x", "y", "z"]}]))


def test_joining_control_nets_of_other_degrees_is_an_error():
    """Through the API the control points stay each patch's own, so a linear face against a quadratic one
    cannot be joined; the error says to elevate first, which works."""
    a = nurbs.brick([0, 0, 0], [1, 1, 1], degree=1).patches[0]
    b = nurbs.brick([1, 0, 0], [2, 1, 1], degree=2).patches[0]
    with pytest.raises(ValueError, match=r"patches\[1\] meets patches\[0\].*elevate the patches to one degree"):
        nurbs.bezier_mesh(NurbsSolid([a, b]))
    mesh = nurbs.bezier_mesh(NurbsSolid([a.elevate(0).elevate(1).elevate(2), b]))
    assert mesh.solid.n_nodes == 5 * 3 * 3


def test_a_degree_above_the_registry_names_the_patch_and_what_is_supported():
    patch = wavy_patch((2, 2, 2))
    with pytest.raises(ValueError, match=r"patches\[1\]: degree 5 in direction 2; supported are degrees 1 to 4 per "
                                         r"direction, elevated exactly to the element types nurbs27 \(degree 2\), "
                                         r"nurbs64 \(degree 3\), nurbs125 \(degree 4\)"):
        nurbs.bezier_mesh(NurbsSolid([patch, patch.elevate(2, 3)]))
    assert common_degree([(1, 1, 1), (1, 2, 1)]) == 2 and common_degree((1, 1, 3)) == 3
    assert common_degree([(1, 1, 1), (4, 2, 1)]) == 4


def test_generators_take_degrees_per_direction():
    pipe = nurbs.hollow_cylinder(RI, RO, L, angle=90.0, elements=(1, 1, 1), degree=(1, 2, 1))
    assert pipe.patches[0].degrees == (1, 2, 1) and pipe.n_control == 2 * 3 * 2
    x = nurbs.bezier_mesh(pipe).solid
    xi = np.random.default_rng(2).uniform(-1.0, 1.0, (20, 3))
    r = np.hypot(*element_values(x, xi, x.points)[0, :, :2].T)
    assert np.all((r > RI - 1e-15) & (r < RO + 1e-15))
    edge = element_values(x, np.column_stack([-np.ones(20), xi[:, 1:]]), x.points)[0]
    assert np.abs(np.hypot(edge[:, 0], edge[:, 1]) - RI).max() < 1e-15             # the exact circle
    with pytest.raises(ValueError, match="must be >= 2 in direction 1"):
        nurbs.hollow_cylinder(RI, RO, L, degree=(2, 1, 2))
    assert nurbs.brick([0, 0, 0], [1, 1, 1], degree=(1, 3, 2)).patches[0].degrees == (1, 3, 2)


@pytest.mark.parametrize("degree", [(2, 2), (2, 2, 2, 2), [[2, 2, 2]], 2.5])
def test_a_degree_of_the_wrong_shape_is_named(degree):
    """One degree or three: anything else is a ValueError naming the key (not numpy's broadcasting
    message)."""
    with pytest.raises(ValueError, match="degree: expected an integer or three"):
        nurbs.brick([0, 0, 0], [1, 1, 1], degree=degree)
