"""Solid elements and materials: consistency (finite differences), patch tests, rigid motions,
closed-form stretches, volume, mixed meshes, thread independence."""
import numba
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

import mortar1d3d as m13
from mortar1d3d.errors import MeshError
from mortar1d3d.physics.materials import MATERIALS, material, stress_tangent
from mortar1d3d.physics.solid import InvertedElementsError, SolidModel

from naive import central_differences

ELEMENTS = [n for n, d in m13.elements.SOLID_ELEMENTS.items() if not d.rational]     # nurbs27: test_nurbs_model
HYPERELASTIC = ["saint_venant_kirchhoff", "neo_hooke"]
E_MODULUS, NU = 200.0, 0.3


def single_element(element, seed=0, amplitude=0.06):
    """The unit cube as the elements of one grid cell (a hexahedron, six tetrahedra, ...), every node
    moved at random."""
    mesh = m13.generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), element)
    rng = np.random.default_rng(seed)
    return m13.SolidMesh(mesh.points + amplitude * rng.uniform(-1, 1, mesh.points.shape), mesh.cells)


def random_displacement(model, scale=0.05, seed=1):
    return scale * np.random.default_rng(seed).uniform(-1.0, 1.0, model.n_dofs)


def affine(points, G, c=(0.0, 0.0, 0.0)):
    return (points @ np.asarray(G).T + np.asarray(c)).reshape(-1)


TET10_EDGES = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [1, 3], [2, 3]])    # VTK nodes 4..9


def distorted_box(element, cells, amplitude, seed=0):
    """``generate.distort`` of a box; tetra10 keep straight edges (mid-edge nodes re-centred).

    The 4-point rule integrates ∫ ∇N dV exactly only for straight-sided tetra10 (constant J);
    on curved ones the patch test holds only up to the quadrature error (about 1e-4 here).
    """
    mesh = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), cells, element), amplitude=amplitude,
                                seed=seed)
    if element != "tetra10":
        return mesh
    points = mesh.points.copy()
    conn = mesh.cells["tetra10"]
    points[conn[:, 4:]] = 0.5 * (points[conn[:, TET10_EDGES[:, 0]]] + points[conn[:, TET10_EDGES[:, 1]]])
    return m13.SolidMesh(points, mesh.cells, point_sets=mesh.point_sets)


def interior_nodes(mesh):
    boundary = np.unique(np.concatenate([mesh.point_sets[f"{a}_{s}"] for a in "xyz" for s in ("min", "max")]))
    return np.setdiff1d(np.arange(mesh.n_nodes), boundary)


# ----------------------------------------------------------------------------- materials

def test_material_parameters_and_validation():
    mat = material("neo_hooke", 200.0, 0.25)
    assert mat.code == MATERIALS.index("neo_hooke")
    assert mat.lam == pytest.approx(200.0 * 0.25 / (1.25 * 0.5))
    assert mat.mu == pytest.approx(80.0)
    with pytest.raises(ValueError, match="linear_elastic, saint_venant_kirchhoff, neo_hooke"):
        material("mooney", 1.0, 0.3)
    for E in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="Young's modulus"):
            material("neo_hooke", E, 0.3)
    for nu in (0.5, -1.0, 0.7, np.nan):
        with pytest.raises(ValueError, match="Poisson's ratio"):
            material("saint_venant_kirchhoff", 1.0, nu)


def _stretch_from_strain(E):
    """F = U = sqrt(I + 2E) (symmetric), so that ½(FᵀF - I) = E."""
    w, V = np.linalg.eigh(np.eye(3) + 2.0 * E)
    return (V * np.sqrt(w)) @ V.T


@pytest.mark.parametrize("name", MATERIALS)
def test_stress_tangent_against_finite_differences(name):
    """S = ∂W/∂E and C = ∂S/∂E (Voigt, engineering shear) by central differences in E."""
    mat = material(name, E_MODULUS, NU)
    rng = np.random.default_rng(3)
    E0 = 0.05 * rng.uniform(-1, 1, (3, 3))
    E0 = 0.5 * (E0 + E0.T)
    S = np.empty((3, 3))
    C = np.empty((6, 6))
    stress_tangent(mat.code, mat.lam, mat.mu, _stretch_from_strain(E0) - np.eye(3), S, C)
    S0, C0 = S.copy(), C.copy()
    voigt = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]
    h = 1e-6
    C_fd = np.empty((6, 6))
    for q, (K, L) in enumerate(voigt):
        dE = np.zeros((3, 3))
        dE[K, L] = dE[L, K] = h if K == L else h / 2       # engineering shear: γ = 2 E_KL
        Sp, Sm = np.empty((3, 3)), np.empty((3, 3))
        Wp = stress_tangent(mat.code, mat.lam, mat.mu, _stretch_from_strain(E0 + dE) - np.eye(3), Sp, np.empty((6, 6)))
        Wm = stress_tangent(mat.code, mat.lam, mat.mu, _stretch_from_strain(E0 - dE) - np.eye(3), Sm, np.empty((6, 6)))
        dW = (Wp - Wm) / (2 * h)
        assert dW == pytest.approx(S0[K, L], rel=1e-7, abs=1e-9 * E_MODULUS)
        C_fd[:, q] = [(Sp[I, J] - Sm[I, J]) / (2 * h) for I, J in voigt]
    assert np.abs(C0 - C_fd).max() <= 1e-7 * np.abs(C0).max()
    assert np.array_equal(C0, C0.T)


def test_linear_elastic_with_finite_deformation_is_svk_and_neo_hooke_reports_inversion():
    F = np.array([[1.1, 0.2, 0.0], [0.05, 0.9, 0.1], [0.0, -0.1, 1.05]])
    out = {}
    for name in ("linear_elastic", "saint_venant_kirchhoff"):
        mat = material(name, E_MODULUS, NU)
        S, C = np.empty((3, 3)), np.empty((6, 6))
        W = stress_tangent(mat.code, mat.lam, mat.mu, F - np.eye(3), S, C)
        out[name] = (W, S, C)
    for a, b in zip(out["linear_elastic"], out["saint_venant_kirchhoff"]):
        assert np.array_equal(a, b)
    mat = material("neo_hooke", E_MODULUS, NU)
    S, C = np.zeros((3, 3)), np.zeros((6, 6))
    W = stress_tangent(mat.code, mat.lam, mat.mu, np.diag([1.0, 1.0, -1.0]) - np.eye(3), S, C)
    assert np.isnan(W) and np.isnan(S).all() and np.isnan(C).all()


# ----------------------------------------------------------------------------- consistency

@pytest.mark.parametrize("element", ELEMENTS)
@pytest.mark.parametrize("name", HYPERELASTIC)
def test_forces_and_tangent_against_finite_differences(element, name):
    model = SolidModel(single_element(element), material(name, E_MODULUS, NU))
    u = random_displacement(model)
    f, K = model.evaluate(u)
    h = 1e-6
    f_fd = central_differences(model.energy, u, h)
    assert np.linalg.norm(f - f_fd) <= 1e-6 * np.linalg.norm(f)
    K_fd = central_differences(lambda v: model.evaluate(v, tangent=False)[0], u, h).T
    Kd = K.toarray()
    assert np.linalg.norm(Kd - K_fd) <= 1e-6 * np.linalg.norm(Kd)
    assert np.array_equal(Kd, Kd.T)                      # mirrored: exactly symmetric


@pytest.mark.parametrize("element", ELEMENTS)
def test_linear_kinematics_forces_energy_and_cached_tangent(element):
    model = SolidModel(single_element(element), material("linear_elastic", E_MODULUS, NU), kinematics="linear")
    u = random_displacement(model)
    f, K = model.evaluate(u)
    assert np.allclose(f, K @ u, rtol=0, atol=1e-14 * np.abs(f).max())
    assert model.energy(u) == pytest.approx(0.5 * u @ f, rel=1e-12)
    f_fd = central_differences(model.energy, u, 1e-6)
    assert np.linalg.norm(f - f_fd) <= 1e-6 * np.linalg.norm(f)
    f2, K2 = model.evaluate(2.0 * u)
    assert K2 is K and np.allclose(f2, 2.0 * f, rtol=1e-14, atol=0)
    assert (model.n_evaluations, model.n_tangents) == (2, 1)
    # linear K has the rigid body modes as its null space (6 zero eigenvalues)
    eig = np.linalg.eigvalsh(K.toarray())
    assert np.sum(np.abs(eig) < 1e-9 * eig.max()) == 6 and eig.min() > -1e-9 * eig.max()


# ----------------------------------------------------------------------------- patch tests

def _closed_form(name, F):
    """(E, σ) of a homogeneous deformation F by the textbook formulas."""
    mat = material(name, E_MODULUS, NU)
    lam, mu = mat.lam, mat.mu
    C = F.T @ F
    E = 0.5 * (C - np.eye(3))
    J = np.linalg.det(F)
    if name == "neo_hooke":
        S = mu * (np.eye(3) - np.linalg.inv(C)) + lam * np.log(J) * np.linalg.inv(C)
    else:
        S = lam * np.trace(E) * np.eye(3) + 2 * mu * E
    return E, F @ S @ F.T / J


@pytest.mark.parametrize("element", ELEMENTS)
@pytest.mark.parametrize("kinematics", ["nonlinear", "linear"])
def test_patch_test(element, kinematics):
    mesh = distorted_box(element, (2, 2, 2), amplitude=0.15, seed=4)
    name = "neo_hooke" if kinematics == "nonlinear" else "linear_elastic"
    model = SolidModel(mesh, material(name, E_MODULUS, NU), kinematics=kinematics)
    G = np.array([[0.08, -0.03, 0.02], [0.05, -0.04, 0.01], [-0.02, 0.06, 0.03]])
    u = affine(mesh.points, G, c=(0.1, -0.2, 0.3))
    f, _ = model.evaluate(u, tangent=False)
    fields = model.cell_fields(u)
    if kinematics == "nonlinear":
        E, sigma = _closed_form(name, np.eye(3) + G)
    else:
        E = 0.5 * (G + G.T)
        sigma = material(name, E_MODULUS, NU).lam * np.trace(E) * np.eye(3) + 2 * material(name, E_MODULUS, NU).mu * E
    assert np.abs(fields["green_lagrange_strain"] - E).max() <= 1e-13
    assert np.abs(fields["cauchy_stress"] - sigma).max() <= 1e-12 * np.abs(sigma).max()
    inner = interior_nodes(mesh)
    assert len(inner) > 0
    assert np.abs(f.reshape(-1, 3)[inner]).max() <= 1e-12 * np.abs(f).max()
    assert np.abs(f).max() > 1e-3 * E_MODULUS * 0.01        # the boundary does carry the load


# ----------------------------------------------------------------------------- rigid motion

def _rotation(axis, angle):
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * Kx + (1 - np.cos(angle)) * Kx @ Kx


@pytest.mark.parametrize("element", ELEMENTS)
@pytest.mark.parametrize("name", HYPERELASTIC)
def test_rigid_rotation_is_stress_free_and_tangent_at_rest_is_linear(element, name):
    mesh = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (2, 1, 1), element), amplitude=0.1)
    model = SolidModel(mesh, material(name, E_MODULUS, NU))
    R = _rotation((1.0, 2.0, 0.5), np.pi / 2)
    u = affine(mesh.points, R - np.eye(3), c=(0.3, 0.0, -1.0))
    f, K_rot = model.evaluate(u)
    scale = E_MODULUS * model.volume()
    assert abs(model.energy(u)) <= 1e-13 * scale
    assert np.abs(f).max() <= 1e-13 * scale
    # a stretch of the same size does produce forces (the checks above can fail)
    assert np.abs(model.evaluate(affine(mesh.points, 0.01 * np.eye(3)), tangent=False)[0]).max() > 1e-3 * scale * 0.01
    K_nl = model.evaluate(np.zeros(model.n_dofs))[1]
    K_lin = SolidModel(mesh, material(name, E_MODULUS, NU), kinematics="linear").evaluate(np.zeros(model.n_dofs))[1]
    assert abs(K_nl - K_lin).max() <= 1e-13 * abs(K_lin).max()
    # the tangent of the rotated state is the rotated linear tangent: K_rot = Q K_lin Qᵀ
    Q = sp.kron(sp.identity(mesh.n_nodes), sp.csr_matrix(R))
    assert abs(K_rot - Q @ K_lin @ Q.T).max() <= 1e-12 * abs(K_lin).max()


# ----------------------------------------------------------------------------- closed forms

def _uniaxial_stress(name, stretch):
    """Lateral stretch with S22 = S33 = 0 and the 1st PK stress P11, by hand."""
    mat = material(name, E_MODULUS, NU)
    lam, mu = mat.lam, mat.mu
    if name == "saint_venant_kirchhoff":
        E11 = 0.5 * (stretch ** 2 - 1)
        lateral = np.sqrt(1 - 2 * NU * E11)                   # E22 = -ν E11 under uniaxial S
        return lateral, stretch * E_MODULUS * E11
    def S22(l2):
        return mu * (1 - 1 / l2 ** 2) + lam * np.log(stretch * l2 ** 2) / l2 ** 2
    lateral = brentq(S22, 0.5, 1.5, xtol=1e-15, rtol=1e-15)
    J = stretch * lateral ** 2
    return lateral, stretch * (mu * (1 - 1 / stretch ** 2) + lam * np.log(J) / stretch ** 2)


@pytest.mark.parametrize("element", ["hexahedron", "hexahedron27", "tetra10"])
@pytest.mark.parametrize("name", HYPERELASTIC)
def test_uniaxial_stretch_reactions_match_closed_form(element, name):
    mesh = distorted_box(element, (2, 2, 2), amplitude=0.1)
    model = SolidModel(mesh, material(name, E_MODULUS, NU))
    stretch = 1.3
    lateral, P11 = _uniaxial_stress(name, stretch)
    u = affine(mesh.points, np.diag([stretch - 1, lateral - 1, lateral - 1]))
    f = model.evaluate(u, tangent=False)[0].reshape(-1, 3)
    x_max, x_min, y_max = (mesh.point_sets[k] for k in ("x_max", "x_min", "y_max"))
    assert f[x_max, 0].sum() == pytest.approx(P11 * 1.0, rel=1e-12)      # reference area 1
    assert f[x_min, 0].sum() == pytest.approx(-P11, rel=1e-12)
    assert abs(f[y_max, 1].sum()) <= 1e-12 * abs(P11)                    # laterally free
    assert abs(f[:, 1:].sum()) <= 1e-12 * abs(P11)


# ----------------------------------------------------------------------------- volume, loads

@pytest.mark.parametrize("element", ELEMENTS)
def test_volume_and_body_force(element):
    lower, upper = np.array([0.5, -1.0, 2.0]), np.array([2.0, 0.5, 2.75])
    exact = np.prod(upper - lower)
    mesh = m13.generate.box(lower, upper, (2, 3, 2), element)
    model = SolidModel(mesh, material("neo_hooke", E_MODULUS, NU))
    assert model.volume() == pytest.approx(exact, rel=1e-14)
    if element != "tetra10":   # 4-point rule: det J of curved tetra10 (cubic) is not integrated exactly
        distorted = SolidModel(m13.generate.distort(mesh, amplitude=0.15), model.material)
        assert distorted.volume() == pytest.approx(exact, rel=1e-13)
    b = np.array([1.0, -2.0, 9.81])
    fb = model.body_force(b).reshape(-1, 3)
    assert np.allclose(fb.sum(axis=0), b * exact, rtol=1e-13, atol=0)
    # Σ_a (∫ N_a dV) X_a = ∫ X dV: the first moment of the box, exactly
    centroid = 0.5 * (lower + upper)
    assert np.allclose(model.nodal_volumes() @ mesh.points, centroid * exact, rtol=1e-13, atol=0)
    with pytest.raises(ValueError, match="b must be 3 finite numbers"):
        model.body_force([1.0, np.nan, 0.0])


# ----------------------------------------------------------------------------- mixed meshes

def test_mixed_mesh_equals_its_parts():
    a = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (2, 2, 1), "hexahedron"), amplitude=0.1)
    b = m13.generate.box((2, 0, 0), (3, 1, 1), (1, 1, 1), "tetra10")
    c = m13.generate.box((0, 2, 0), (1, 3, 1), (1, 1, 1), "hexahedron27")
    parts = [a, b, c]
    offsets = np.cumsum([0] + [p.n_nodes for p in parts])
    mixed = m13.SolidMesh(np.vstack([p.points for p in parts]),
                          {p.blocks[0][0].name: p.blocks[0][1] + o for p, o in zip(parts, offsets)})
    mat = material("neo_hooke", E_MODULUS, NU)
    model = SolidModel(mixed, mat)
    assert model.volume() == pytest.approx(3.0, rel=1e-14)
    u = random_displacement(model, scale=0.03, seed=7)
    f, K = model.evaluate(u)
    blocks = []
    for p, lo, hi in zip(parts, offsets[:-1], offsets[1:]):
        fp, Kp = SolidModel(p, mat).evaluate(u[3 * lo:3 * hi])
        assert np.allclose(f[3 * lo:3 * hi], fp, rtol=0, atol=1e-13 * np.abs(fp).max())
        blocks.append(Kp)
    assert abs(K - sp.block_diag(blocks)).max() <= 1e-13 * abs(K).max()
    assert model.energy(u) == pytest.approx(sum(SolidModel(p, mat).energy(u[3 * lo:3 * hi])
                                                for p, lo, hi in zip(parts, offsets[:-1], offsets[1:])), rel=1e-13)


# ----------------------------------------------------------------------------- determinism, errors

def test_bit_identical_for_one_and_two_threads():
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    mesh = m13.generate.distort(m13.generate.box((0, 0, 0), (1, 1, 1), (5, 4, 4), "hexahedron"), amplitude=0.1)
    model = SolidModel(mesh, material("neo_hooke", E_MODULUS, NU), assembly_block=3)
    assert model.n_colours >= 3 and len(model._colour_blocks) >= 20
    u = random_displacement(model, scale=0.02, seed=11)
    default = numba.get_num_threads()
    results = []
    try:
        for threads in (1, 2, 1):
            numba.set_num_threads(threads)
            f, K = model.evaluate(u)
            results.append((f, K, model.energy(u), model.cell_fields(u)["cauchy_stress"]))
    finally:
        numba.set_num_threads(default)
    (f1, K1, e1, s1), (f2, K2, e2, s2) = results[0], results[1]
    assert np.array_equal(f1, f2) and np.array_equal(K1.data, K2.data) and np.array_equal(K1.indices, K2.indices)
    assert e1 == e2 and np.array_equal(s1, s2)
    assert np.array_equal(results[2][1].data, K1.data)
    assert abs(K1 - K1.T).max() == 0.0


def test_inverted_deformation_raises_with_element_ids():
    mesh = m13.generate.box((0, 0, 0), (1, 1, 1), (3, 1, 1), "hexahedron")
    for name in HYPERELASTIC:
        model = SolidModel(mesh, material(name, E_MODULUS, NU))
        u = np.zeros((mesh.n_nodes, 3))
        u[mesh.point_sets["x_max"], 0] = -1.5     # the last element turns inside out
        with pytest.raises(InvertedElementsError, match=r"1 solid elements: 2") as info:
            model.evaluate(u.reshape(-1))
        assert info.value.elements.tolist() == [2]
        with pytest.raises(InvertedElementsError):
            model.energy(u.reshape(-1))


def test_model_input_validation_and_counters():
    mesh = m13.generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), "hexahedron")
    mat = material("saint_venant_kirchhoff", E_MODULUS, NU)
    with pytest.raises(ValueError, match="unknown kinematics"):
        SolidModel(mesh, mat, kinematics="small")
    with pytest.raises(TypeError, match="Material"):
        SolidModel(mesh, "neo_hooke")
    model = SolidModel(mesh, mat)
    assert model.n_dofs == 24
    with pytest.raises(ValueError, match="24 entries"):
        model.evaluate(np.zeros(23))
    model.evaluate(np.zeros(24))
    model.evaluate(np.zeros(24), tangent=False)
    f, K = model.evaluate(np.zeros(24), tangent=False)
    assert K is None and (model.n_evaluations, model.n_tangents) == (3, 1)
    assert isinstance(MeshError("x"), ValueError)
