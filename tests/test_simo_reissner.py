"""Simo–Reissner beam (herm2line3): rotation maps, derivatives, invariance, closed-form cantilevers."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

from mortar1d3d import BeamMesh
from mortar1d3d.physics import rotations as rot
from mortar1d3d.physics.simo_reissner import (RotationRangeError, Section, SimoReissnerBeam, check_triads,
                                              reference_triads)

from naive import central_differences, rotation_exp, rotation_log, skew_matrix, spin_jacobian


# -- helpers -----------------------------------------------------------------------------------------

def exp(psi):
    R = np.empty((3, 3), dtype=np.asarray(psi).dtype)
    rot.exp(np.asarray(psi), R)
    return R


def log(R):
    psi = np.empty(3, dtype=np.asarray(R).dtype)
    rot.log(np.ascontiguousarray(R), psi)
    return psi


def jacobian(psi):
    T = np.empty((3, 3))
    rot.jacobian(np.asarray(psi, dtype=float), T)
    return T


def jacobian_inverse(psi):
    T = np.empty((3, 3))
    rot.jacobian_inverse(np.asarray(psi, dtype=float), T)
    return T


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


#: rotation vector sizes: round-off small, series range, both sides of the series limit √0.5,
#: large, and just below π
SIZES = (1e-9, 1e-4, 0.3, 0.7, 0.72, 2.0, 3.0, np.pi - 1e-7)


def sample_vectors(seed=0, per_size=4):
    rng = np.random.default_rng(seed)
    return [unit(rng.normal(size=3)) * a for a in SIZES for _ in range(per_size)]


def straight_beam(n, length=1.0, direction=(1.0, 0.0, 0.0)):
    d = unit(direction)
    return BeamMesh.from_curve(lambda s: s * d, lambda s: d, 0.0, length, n)


def arc_beam(n, radius=1.0, angle=np.pi / 2):
    return BeamMesh.from_curve(lambda s: radius * np.array([np.sin(s), 1 - np.cos(s), 0.0]),
                               lambda s: np.array([np.cos(s), np.sin(s), 0.0]), 0.0, angle, n)


def helix_beam(n, radius=0.3, pitch=0.1, turns=0.35):
    return BeamMesh.from_curve(lambda s: np.array([radius * np.cos(s), radius * np.sin(s), pitch * s]),
                               lambda s: np.array([-radius * np.sin(s), radius * np.cos(s), pitch]),
                               0.0, 2 * np.pi * turns, n)


#: unequal stiffnesses, so that a wrong axis or a swapped component shows
SECTION = Section(EA=10.0, GA2=4.0, GA3=3.0, GI_T=0.5, EI2=0.7, EI3=0.9)


def deformed_state(model, seed=1, size=0.05, turn=0.3):
    rng = np.random.default_rng(seed)
    return size * rng.normal(size=model.n_centreline_dofs), turn * rng.normal(size=(model.n_rotation_nodes, 3))


def perturbed(model, d, psi, x):
    """State ``(d, ψ) ⊕ x``: centreline part added, rotation part as spatial spins."""
    nc = model.n_centreline_dofs
    return d + x[:nc], model.update(psi, x[nc:].reshape(-1, 3))


# -- rotation maps -----------------------------------------------------------------------------------

def test_exp_log_round_trip():
    worst_exp, worst_log = 0.0, 0.0
    for psi in sample_vectors():
        R = exp(psi)
        worst_exp = max(worst_exp, np.abs(R - rotation_exp(psi)).max())
        worst_log = max(worst_log, np.abs(log(R) - psi).max())
        assert np.abs(log(R) - rotation_log(R)).max() < 1e-7
    assert worst_exp < 4e-15          # expm (scaling and squaring) against Rodrigues
    assert worst_log < 1e-14
    # exactly π and beyond: |ψ| ≤ π, the same rotation
    for psi in (np.array([np.pi, 0, 0]), unit([1, 2, 3]) * 4.0, unit([-1, 0.5, 2]) * 2 * np.pi - 1e-3):
        p = log(exp(psi))
        assert np.linalg.norm(p) <= np.pi + 1e-15
        assert np.abs(exp(p) - exp(psi)).max() < 1e-14


def test_jacobians_against_finite_differences():
    rng = np.random.default_rng(3)
    for psi in sample_vectors(seed=2, per_size=2):
        T = jacobian(psi)
        assert np.abs(T - spin_jacobian(psi)).max() < 1e-9
        assert np.abs(jacobian_inverse(psi) @ T - np.eye(3)).max() < 1e-14
        # the directional derivative of T, transposed
        v, u = rng.normal(size=3), rng.normal(size=3)
        out = np.empty(3)
        rot.jacobian_derivative_transpose(psi, v, u, out, np.empty(9))
        fd = central_differences(lambda s: jacobian(psi + s[0] * v).T @ u, np.zeros(1), 1e-6)[0]
        assert np.abs(out - fd).max() < 1e-9 * max(1.0, np.abs(fd).max())


def test_complex_step_of_log_is_the_inverse_jacobian():
    """Im log(exp(i h v) exp(ψ)) / h = T(ψ)⁻¹ v: log is complex-analytic on every branch (near 0,
    both sides of the series limits, near π where the quaternion's scalar part is small)."""
    rng = np.random.default_rng(4)
    h = 1e-30
    for psi in sample_vectors(seed=5, per_size=2):
        v = rng.normal(size=3)
        R = exp(1j * h * v) @ exp(psi.astype(complex))
        got = log(R).imag / h
        want = jacobian_inverse(psi) @ v
        assert np.abs(got - want).max() < 1e-12 * max(1.0, np.abs(want).max()), np.linalg.norm(psi)


def test_compose_is_the_product_of_rotations():
    rng = np.random.default_rng(6)
    psi = np.array(sample_vectors(seed=7, per_size=1))
    dtheta = rng.normal(size=psi.shape)
    out = np.empty_like(psi)
    rot.compose_rows(psi, dtheta, out)
    for p, d, o in zip(psi, dtheta, out):
        assert np.abs(rotation_exp(o) - rotation_exp(d) @ rotation_exp(p)).max() < 1e-14
        assert np.linalg.norm(o) <= np.pi + 1e-15


def test_skew_and_axial():
    v = np.array([0.3, -1.2, 2.0])
    S = np.empty((3, 3))
    rot.skew(v, S)
    assert np.array_equal(S, skew_matrix(v))
    out = np.empty(3)
    rot.axial(S + np.diag([1.0, 2.0, 3.0]), out)
    assert np.array_equal(out, v)


# -- residual and tangent ------------------------------------------------------------------------------

@pytest.mark.parametrize("beams", [straight_beam(3), arc_beam(3), helix_beam(3)], ids=["straight", "arc", "helix"])
def test_reference_configuration_is_stress_free(beams):
    model = SimoReissnerBeam(beams, SECTION)
    d, psi = np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3))
    f, _ = model.evaluate(d, psi)
    assert np.abs(f).max() == 0.0
    assert model.energy(d, psi) == 0.0
    s = model.sample(d, psi, np.linspace(-1, 1, 5))
    assert np.abs(s["F"]).max() < 1e-13 and np.abs(s["M"]).max() < 1e-13


RULES = {"gauss": "gauss", "lobatto": "lobatto3", "mixed": ["lobatto3", "gauss", "lobatto3"]}


@pytest.mark.parametrize("rule", RULES.values(), ids=RULES.keys())
def test_tangent_against_central_differences(rule):
    model = SimoReissnerBeam(helix_beam(3), SECTION, force_rule=rule)
    d, psi = deformed_state(model)
    f, K = model.evaluate(d, psi)
    K = K.toarray()
    fd = central_differences(lambda x: model.evaluate(*perturbed(model, d, psi, x), tangent=False)[0],
                             np.zeros(model.n_dofs), 1e-6).T
    assert np.abs(K - fd).max() < 1e-9 * np.abs(K).max()
    assert np.abs(K - K.T).max() > 1e-2 * np.abs(K).max()      # away from equilibrium: not symmetric


@pytest.mark.parametrize("rules", [dict(force_gauss=2), dict(force_rule="lobatto3"),
                                   dict(force_rule=RULES["mixed"])], ids=["gauss2", "lobatto", "mixed"])
def test_residual_is_the_energy_derivative(rules):
    model = SimoReissnerBeam(helix_beam(3), SECTION, n_gauss=3, **rules)
    d, psi = deformed_state(model, seed=2)
    f, _ = model.evaluate(d, psi, tangent=False)
    fd = central_differences(lambda x: model.energy(*perturbed(model, d, psi, x)), np.zeros(model.n_dofs), 1e-6)
    assert np.abs(f - fd).max() < 1e-8 * np.abs(f).max()


# -- the 3-point Gauss–Lobatto force rule (4C's BEAM3R) -----------------------------------------------

@pytest.mark.parametrize("beams", [straight_beam(3), arc_beam(3), helix_beam(3)], ids=["straight", "arc", "helix"])
def test_lobatto_force_rule_keeps_the_reference_stress_free(beams):
    """Γ0 and K0 are taken at the points of the terms that use them: no force in the reference."""
    model = SimoReissnerBeam(beams, SECTION, force_rule="lobatto3")
    d, psi = np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3))
    f, _ = model.evaluate(d, psi)
    assert np.abs(f).max() == 0.0 and model.energy(d, psi) == 0.0


def test_lobatto_force_rule_samples_the_force_term_at_ends_and_middle():
    """The energy is the force term at η = -1, 0, 1 (weights 1/3, 4/3, 1/3) plus the moment term at
    the 3 Gauss points, both from the strains of ``sample`` (a straight beam: ds = L/2 dη)."""
    beams = straight_beam(2, length=2.0)
    model = SimoReissnerBeam(beams, SECTION, force_rule="lobatto3")
    d, psi = deformed_state(model, seed=3)
    x, w = np.array([-1.0, 0.0, 1.0]), np.array([1.0, 4.0, 1.0]) / 3.0
    g, wg = np.polynomial.legendre.leggauss(3)
    F, M = model.sample(d, psi, x), model.sample(d, psi, g)
    J = 0.5                                               # elements of length 1
    expected = 0.5 * J * (np.einsum("p,epi,i->", w, F["Gamma"] ** 2, SECTION.force_stiffness)
                          + np.einsum("p,epi,i->", wg, M["K"] ** 2, SECTION.moment_stiffness))
    assert model.energy(d, psi) == pytest.approx(expected, rel=1e-12)
    gauss = SimoReissnerBeam(beams, SECTION)
    assert abs(gauss.energy(d, psi) - model.energy(d, psi)) > 1e-3 * model.energy(d, psi)


def test_force_rule_is_checked():
    with pytest.raises(ValueError, match="force_rule of elements 1: 'lobatto' is not one of"):
        SimoReissnerBeam(straight_beam(2), SECTION, force_rule=["gauss", "lobatto"])
    with pytest.raises(ValueError, match=r"one per element \(2\), got 3"):
        SimoReissnerBeam(straight_beam(2), SECTION, force_rule=["gauss"] * 3)


# -- Lagrange virtual spins (4C's BEAM3R residual) -------------------------------------------------------

def lagrange_spin_rows(model, d, psi, force_points, force_weights):
    """Spin rows ``Σ_g w_g J_g [L_k (n × r_s) + L_k,s m]`` per rotation node, written out from the
    model's own strain sampling (not from the kernel's residual code)."""
    from mortar1d3d.elements.beam import evaluate as beam_functions
    from mortar1d3d.physics.simo_reissner import _lagrange_tables
    eta_m, w_m = np.polynomial.legendre.leggauss(model.n_gauss)
    sm, sf = model.sample(d, psi, eta_m), model.sample(d, psi, force_points)
    lag_f = _lagrange_tables(force_points)[0]
    dlag_m = _lagrange_tables(eta_m)[1]
    dH = beam_functions(model.beams.element_type, np.asarray(force_points)[None, :],
                        model.beams.lengths[:, None], derivative=1)[..., :4]
    q = model._coefficients(np.concatenate([model._q0 + d, np.zeros(3 * model.n_rotation_nodes)]))
    q0 = model._coefficients(np.concatenate([model._q0, np.zeros(3 * model.n_rotation_nodes)]))
    rp, J = np.einsum("egk,eki->egi", dH, q), np.linalg.norm(np.einsum("egk,eki->egi", dH, q0), axis=2)
    rows = np.zeros((model.n_rotation_nodes, 3))
    for e, nodes in enumerate(model.rotation_nodes):
        for k, node in enumerate(nodes):
            for g in range(len(force_points)):
                rows[node] += force_weights[g] * lag_f[g, k] * np.cross(sf["n"][e, g], rp[e, g] / J[e, g]) * J[e, g]
            for g in range(model.n_gauss):
                rows[node] += w_m[g] * dlag_m[g, k] * sm["m"][e, g]
    return rows.ravel()


@pytest.mark.parametrize("rule", ["gauss", "lobatto3"])
def test_lagrange_virtual_spins_are_the_internal_force_of_jelenic_and_crisfield(rule):
    """``virtual_spins = "lagrange"``: the centreline rows are unchanged, the spin rows are
    Σ w J [L_k (n × r_s) + L_k,s m] (Jelenić & Crisfield 1999, eq. (4.3); 4C's BEAM3R) and differ
    from the energy's gradient where the triads do not turn about one axis."""
    exact = SimoReissnerBeam(helix_beam(3), SECTION, force_rule=rule)
    model = SimoReissnerBeam(helix_beam(3), SECTION, force_rule=rule, virtual_spins="lagrange")
    d, psi = deformed_state(model, seed=2)
    f, _ = model.evaluate(d, psi, tangent=False)
    f_exact, _ = exact.evaluate(d, psi, tangent=False)
    nc = model.n_centreline_dofs
    assert np.array_equal(f[:nc], f_exact[:nc])
    points = (np.array([-1.0, 0.0, 1.0]), np.array([1.0, 4.0, 1.0]) / 3) if rule == "lobatto3" else \
        np.polynomial.legendre.leggauss(3)
    expected = lagrange_spin_rows(model, d, psi, *points)
    assert np.abs(f[nc:] - expected).max() < 1e-13 * np.abs(expected).max()
    assert np.abs(f[nc:] - f_exact[nc:]).max() > 1e-2 * np.abs(expected).max()


def test_lagrange_virtual_spins_tangent_against_central_differences():
    model = SimoReissnerBeam(helix_beam(3), SECTION, force_rule=["lobatto3", "gauss", "lobatto3"],
                             virtual_spins="lagrange")
    d, psi = deformed_state(model)
    K = model.evaluate(d, psi)[1].toarray()
    fd = central_differences(lambda x: model.evaluate(*perturbed(model, d, psi, x), tangent=False)[0],
                             np.zeros(model.n_dofs), 1e-6).T
    assert np.abs(K - fd).max() < 1e-9 * np.abs(K).max()


def test_lagrange_and_exact_virtual_spins_agree_for_turns_about_one_axis():
    """Triads all turned about the same axis (a plane problem): Ĩ_k = L_k I, the same residual."""
    beams = straight_beam(3)
    exact = SimoReissnerBeam(beams, SECTION, force_rule="lobatto3")
    model = SimoReissnerBeam(beams, SECTION, force_rule="lobatto3", virtual_spins=["lagrange"] * 3)
    rng = np.random.default_rng(3)
    d = 0.05 * rng.normal(size=model.n_centreline_dofs)
    psi = np.zeros((model.n_rotation_nodes, 3))
    psi[:, 2] = 0.4 * rng.normal(size=model.n_rotation_nodes)
    f, f_exact = model.evaluate(d, psi, tangent=False)[0], exact.evaluate(d, psi, tangent=False)[0]
    assert np.abs(f - f_exact).max() < 1e-14 * np.abs(f).max()
    with pytest.raises(ValueError, match="virtual_spins of elements 0: 'lagrangian' is not one of"):
        SimoReissnerBeam(beams, SECTION, virtual_spins=["lagrangian", "exact", "exact"])


# -- invariance -----------------------------------------------------------------------------------------

def rotation_vector(R):
    psi = np.empty(3)
    rot.log(np.ascontiguousarray(R), psi)
    return psi


def moved_state(model, d, psi, R, c):
    """State of the configuration moved rigidly by ``x ↦ R x + c``: positions, tangents and triads."""
    q = (model.beams.centreline_dofs() + d).reshape(-1, 2, 3) @ R.T
    q[:, 0] += c
    rv = np.tile(rotation_vector(R), (model.n_rotation_nodes, 1))
    return q.ravel() - model.beams.centreline_dofs(), model.update(psi, rv)


R_RIGID = rotation_exp(np.array([0.4, -1.1, 2.0]))
C_RIGID = np.array([3.0, -2.0, 0.5])


@pytest.mark.parametrize("make", [arc_beam, helix_beam], ids=["arc", "helix"])
def test_objectivity(make):
    """A rigid rotation of the deformed state changes no strain, no material resultant and no energy,
    and rotates the residual and the tangent."""
    model = SimoReissnerBeam(make(3), SECTION)
    d, psi = deformed_state(model, seed=3)
    d2, psi2 = moved_state(model, d, psi, R_RIGID, C_RIGID)
    eta = np.linspace(-1, 1, 4)
    a, b = model.sample(d, psi, eta), model.sample(d2, psi2, eta)
    for key in ("Gamma", "K", "F", "M", "axial_force", "curvature"):
        assert np.abs(a[key] - b[key]).max() < 1e-12, key
    assert np.abs(b["n"] - a["n"] @ R_RIGID.T).max() < 1e-12
    assert np.abs(b["triads"] - R_RIGID @ a["triads"]).max() < 1e-13
    assert abs(model.energy(d2, psi2) - model.energy(d, psi)) < 1e-13 * model.energy(d, psi)
    f, K = model.evaluate(d, psi)
    f2, K2 = model.evaluate(d2, psi2)
    B = np.kron(np.eye(model.n_dofs // 3), R_RIGID)
    assert np.abs(f2 - B @ f).max() < 1e-12 * np.abs(f).max()
    assert np.abs(K2.toarray() - B @ K.toarray() @ B.T).max() < 1e-11 * np.abs(K.toarray()).max()


@pytest.mark.parametrize("make", [straight_beam, arc_beam, helix_beam], ids=["straight", "arc", "helix"])
def test_rigid_motion_of_the_reference_is_stress_free(make):
    model = SimoReissnerBeam(make(4), SECTION)
    zero = np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3))
    d, psi = moved_state(model, *zero, R_RIGID, C_RIGID)
    f, _ = model.evaluate(d, psi, tangent=False)
    assert np.abs(f).max() < 1e-13
    assert model.energy(d, psi) < 1e-28


def test_interpolation_is_path_independent():
    """Closed sequences of nodal rotation updates (each node turned and turned back, interleaved, and a
    full turn of every triad in 8 steps) return the strains they started from."""
    model = SimoReissnerBeam(helix_beam(3), SECTION)
    d, psi = deformed_state(model, seed=4)
    eta = np.linspace(-1, 1, 5)
    start = model.sample(d, psi, eta)
    rng = np.random.default_rng(8)
    turns = rng.normal(size=(3, model.n_rotation_nodes, 3))
    p = psi
    for t in turns:
        p = model.update(p, t)
    for t in turns[::-1]:
        p = model.update(p, -t)
    axis = unit([1.0, 2.0, 2.0]) * (np.pi / 4)
    for _ in range(8):
        p = model.update(p, np.tile(axis, (model.n_rotation_nodes, 1)))
    end = model.sample(d, p, eta)
    for key in ("Gamma", "K", "triads"):
        assert np.abs(end[key] - start[key]).max() < 1e-12, key


# -- closed-form cantilevers (linear: one solve with the tangent at the reference) -------------------

E_, G_, A_, I_ = 100.0, 40.0, 0.01, 1e-5
CANTILEVER = Section.from_properties(E_, A_, I_, 2 * I_, 3 * I_, 5 / 6, G=G_)


def linear_cantilever(n, loads, clamp_tangent=False, **rules):
    """Straight cantilever x ∈ [0, 1] clamped at x = 0 (position and triad; and the tangent if
    ``clamp_tangent``), loads ``{dof: value}`` (``("r", node, i)``, ``("theta", rotation node, i)``)."""
    model = SimoReissnerBeam(straight_beam(n), CANTILEVER, **rules)
    nc = model.n_centreline_dofs
    dof = {"r": lambda a, i: 6 * a + i, "t": lambda a, i: 6 * a + 3 + i, "theta": lambda a, i: nc + 3 * a + i}
    F = np.zeros(model.n_dofs)
    for (kind, a, i), value in loads.items():
        F[dof[kind](a, i)] += value
    _, K = model.evaluate(np.zeros(nc), np.zeros((model.n_rotation_nodes, 3)))
    fixed = [0, 1, 2, nc, nc + 1, nc + 2] + ([3, 4, 5] if clamp_tangent else [])
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    u = np.zeros(model.n_dofs)
    u[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    return model, u, dof


@pytest.mark.parametrize("n", [1, 3])
def test_cantilever_end_loads_are_exact(n):
    """Tip moments turn the tip by ML/EI (bending about g2 and g3) and ML/GI_T (torsion); a tip force
    deflects it by PL³/(3EI) + PL/(GA): exact to round-off for any number of elements."""
    M, P = 1e-4, 1e-4
    cases = [(("theta", n, 2), CANTILEVER.EI3), (("theta", n, 1), CANTILEVER.EI2),
             (("theta", n, 0), CANTILEVER.GI_T)]
    for key, stiffness in cases:
        model, u, dof = linear_cantilever(n, {key: M})
        assert u[dof[key[0]](n, key[2])] == pytest.approx(M / stiffness, rel=1e-12)
    model, u, dof = linear_cantilever(n, {("r", n, 1): P})
    assert u[dof["r"](n, 1)] == pytest.approx(P / (3 * CANTILEVER.EI3) + P / CANTILEVER.GA2, rel=1e-12)
    model, u, dof = linear_cantilever(n, {("r", n, 2): P})
    assert u[dof["r"](n, 2)] == pytest.approx(P / (3 * CANTILEVER.EI2) + P / CANTILEVER.GA3, rel=1e-12)


def test_cantilever_distributed_load_converges():
    """Uniform load q: nodal deflections exact (consistent load vector), the deflection inside the
    elements converges at order 4."""
    q = 1e-4
    EI, GA = CANTILEVER.EI3, CANTILEVER.GA2

    def exact(x):
        return q / (24 * EI) * (x ** 4 - 4 * x ** 3 + 6 * x ** 2) + q / GA * (x - x * x / 2)

    errors = []
    for n in (2, 4, 8):
        h = 1.0 / n
        loads = {}
        for e in range(n):
            for key, value in ((("r", e, 1), h / 2), (("t", e, 1), h * h / 12), (("r", e + 1, 1), h / 2),
                               (("t", e + 1, 1), -h * h / 12)):
                loads[key] = loads.get(key, 0.0) + q * value
        model, u, dof = linear_cantilever(n, loads)
        nc = model.n_centreline_dofs
        assert np.abs(u[1:nc:6] - exact(np.linspace(0, 1, n + 1))).max() < 1e-12 * exact(1.0)
        s = model.sample(u[:nc], model.update(np.zeros((model.n_rotation_nodes, 3)), u[nc:]), np.linspace(-1, 1, 7))
        errors.append(np.abs(s["displacement"][..., 1] - exact(s["position"][..., 0])).max() / exact(1.0))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.9), (errors, orders)


def test_agrees_with_the_torsion_free_beam_on_a_slender_straight_cantilever():
    """Tip force on a slender straight cantilever: the Simo–Reissner deflection is the torsion-free
    beam's plus the shear deflection P x / GA, node by node."""
    from mortar1d3d.physics.beam import BeamModel
    n, P = 4, 1e-4
    model, u, dof = linear_cantilever(n, {("r", n, 1): P})
    tf = BeamModel(straight_beam(n), CANTILEVER.EA, CANTILEVER.EI3)
    _, K = tf.evaluate(np.zeros(tf.n_dofs))
    F = np.zeros(tf.n_dofs)
    F[6 * n + 1] = P
    free = np.setdiff1d(np.arange(tf.n_dofs), [0, 1, 2, 4, 5])
    v = np.zeros(tf.n_dofs)
    v[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    x = np.linspace(0, 1, n + 1)
    w_sr, w_tf = u[1:model.n_centreline_dofs:6], v[1::6]
    assert np.abs(w_sr - w_tf - P * x / CANTILEVER.GA2).max() < 1e-12 * w_tf[-1]
    assert (P / CANTILEVER.GA2) / w_tf[-1] > 1e-3       # the shear part is visible, not round-off


# -- nonlinear: roll-up of a cantilever by an end moment --------------------------------------------------

def newton(model, fixed, load, steps, max_iterations=25):
    """Load-stepped Newton with the multiplicative rotation update; ``load(λ)`` (n_dofs,)."""
    nc = model.n_centreline_dofs
    d, psi = np.zeros(nc), np.zeros((model.n_rotation_nodes, 3))
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    for step in range(1, steps + 1):
        f_ext = load(step / steps)
        for _ in range(max_iterations):
            f, K = model.evaluate(d, psi)
            x = np.zeros(model.n_dofs)
            x[free] = -spla.spsolve(K.tocsc()[free][:, free], (f - f_ext)[free])
            d, psi = d + x[:nc], model.update(psi, x[nc:].reshape(-1, 3))
            if np.abs(x).max() < 1e-12:
                break
        else:
            raise AssertionError(f"Newton did not converge in load step {step}")
    return d, psi


@pytest.mark.parametrize("rules, clamp_tangent, bound", [(dict(force_gauss=2), True, 1e-14),
                                                         (dict(), False, 5e-3)], ids=["reduced", "default"])
def test_end_moment_rolls_the_cantilever_into_a_circle(rules, clamp_tangent, bound):
    """M = 2π EI / L rolls a straight cantilever into a full circle: its tip returns to the root with
    its triad turned by 2π. The reduced force rule hits it to round-off; the default rule is within
    its locking error (L/r = 100, 8 elements: 4.0e-3 L)."""
    n = 8
    model = SimoReissnerBeam(straight_beam(n), Section.circular(1.0, 1e-2, nu=0.3), **rules)
    nc = model.n_centreline_dofs
    fixed = [0, 1, 2, nc, nc + 1, nc + 2] + ([3, 4, 5] if clamp_tangent else [])

    def load(lam):
        F = np.zeros(model.n_dofs)
        F[nc + 3 * n + 2] = lam * 2 * np.pi * model.sections[0].EI3
        return F

    d, psi = newton(model, fixed, load, 40)
    tip = model.beams.positions[n] + d[6 * n: 6 * n + 3]
    assert np.linalg.norm(tip) < bound
    assert np.abs(model.triads(psi)[n] - np.eye(3)).max() < max(bound, 1e-12) * 10


# -- reference triads, sections, input checks ---------------------------------------------------------

@pytest.mark.parametrize("make", [straight_beam, arc_beam, helix_beam], ids=["straight", "arc", "helix"])
def test_reference_triads_are_orthonormal_frames_on_the_tangent(make):
    beams = make(6)
    L = reference_triads(beams)
    assert L.shape == (beams.n_nodes + beams.n_elements, 3, 3)
    assert np.abs(np.einsum("kji,kjl->kil", L, L) - np.eye(3)).max() < 1e-14
    assert np.abs(np.linalg.det(L) - 1.0).max() < 1e-14
    assert np.abs(L[: beams.n_nodes, :, 0] - beams.tangents).max() < 1e-15
    mid = np.array([unit(beams.evaluate(e, [1e-7])[0] - beams.evaluate(e, [-1e-7])[0])
                    for e in range(beams.n_elements)])
    assert np.abs(L[beams.n_nodes:, :, 0] - mid).max() < 1e-8


def test_parallel_transport_frames():
    """A planar arc keeps g3 normal to its plane; the helix frame is rotation-minimising: its reference
    twist K0_1 is far below the helix torsion τ (a Frenet frame would twist at τ), and shrinks as h²."""
    arc = reference_triads(arc_beam(5), normal=[0.0, 1.0, 0.0])
    assert np.abs(arc[:, :, 2] - [0.0, 0.0, 1.0]).max() < 1e-15
    radius, pitch = 0.3, 0.1
    tau = pitch / (radius ** 2 + pitch ** 2)
    twist = []
    for n in (4, 8):
        model = SimoReissnerBeam(helix_beam(n, radius, pitch), SECTION)
        twist.append(np.abs(model._K0[..., 0]).max())
    assert twist[0] < 1.1e-2 * tau                  # 4 elements: 1.02e-2 τ
    assert twist[0] / twist[1] > 3.9                # h²
    # the default normal is the coordinate axis least aligned with the first tangent
    assert np.abs(reference_triads(straight_beam(2))[0] - np.eye(3)).max() == 0.0


def test_given_triads_are_checked():
    beams = helix_beam(3)
    L = reference_triads(beams)
    # turned about their tangents: still valid, and the model's energy at the reference is zero
    turn = np.array([rotation_exp(0.3 * g[:, 0]) for g in L])
    model = SimoReissnerBeam(beams, SECTION, reference_triads=turn @ L)
    assert np.abs(model.triads0 - turn @ L).max() < 1e-15
    f, _ = model.evaluate(np.zeros(model.n_centreline_dofs), np.zeros((model.n_rotation_nodes, 3)))
    assert np.abs(f).max() < 1e-14
    bad = L.copy()
    bad[2, :, 1] *= 1.01
    with pytest.raises(ValueError, match="not orthonormal at rotation nodes 2"):
        check_triads(beams, bad)
    bad = L.copy()
    bad[5, :, 2] *= -1.0
    with pytest.raises(ValueError, match="left-handed at rotation nodes 5"):
        check_triads(beams, bad)
    bad = rotation_exp(0.01 * L[4, :, 1]) @ L[4]
    with pytest.raises(ValueError, match="g1 is not the unit reference tangent at rotation nodes 4"):
        check_triads(beams, np.concatenate([L[:4], bad[None], L[5:]]))
    with pytest.raises(ValueError, match=r"shape \(7, 3, 3\)"):
        check_triads(beams, L[:4])
    with pytest.raises(ValueError, match="parallel to the tangent at node 0"):
        reference_triads(straight_beam(2), normal=[2.0, 0.0, 0.0])


def test_sections():
    s = Section.circular(E=200.0, radius=0.5, nu=0.3)
    A, I = np.pi * 0.25, np.pi * 0.0625 / 4
    k = 6 * 1.3 / (7 + 6 * 0.3)
    G = 200.0 / 2.6
    assert (s.EA, s.EI2, s.EI3, s.GI_T) == pytest.approx((200 * A, 200 * I, 200 * I, G * 2 * I), rel=1e-15)
    assert (s.GA2, s.GA3) == pytest.approx((G * k * A, G * k * A), rel=1e-15)
    g = Section.circular(E=200.0, radius=0.5, G=G)            # ν from G: the same shear correction
    assert (g.GA2, g.GI_T) == pytest.approx((s.GA2, s.GI_T), rel=1e-14)
    t = Section.from_properties(E=10.0, A=2.0, I2=3.0, I3=4.0, I_T=5.0, shear_correction=(0.5, 0.25), G=4.0)
    assert (t.EA, t.GA2, t.GA3, t.GI_T, t.EI2, t.EI3) == (20.0, 4.0, 2.0, 20.0, 30.0, 40.0)
    for bad, match in [(dict(E=1.0, radius=1.0), "exactly one of G and nu"),
                       (dict(E=1.0, radius=1.0, G=1.0, nu=0.3), "exactly one of G and nu"),
                       (dict(E=1.0, radius=1.0, nu=0.7), r"section.nu must lie in"),
                       (dict(E=-1.0, radius=1.0, nu=0.3), "section.E"),
                       (dict(E=1.0, radius=np.nan, nu=0.3), "section.radius")]:
        with pytest.raises(ValueError, match=match):
            Section.circular(**bad)
    with pytest.raises(ValueError, match="section.I_T"):
        Section.from_properties(E=1.0, A=1.0, I2=1.0, I3=1.0, I_T=0.0, shear_correction=1.0, nu=0.3)
    with pytest.raises(ValueError, match="section.GA3"):
        Section(EA=1.0, GA2=1.0, GA3=np.inf, GI_T=1.0, EI2=1.0, EI3=1.0)


def test_model_checks_input():
    beams = straight_beam(2)
    with pytest.raises(ValueError, match="hermite"):
        SimoReissnerBeam(BeamMesh.lagrange([[0, 0, 0], [1, 0, 0]], [[0, 1]]), SECTION)
    with pytest.raises(ValueError, match="one per element"):
        SimoReissnerBeam(beams, [SECTION])
    model = SimoReissnerBeam(beams, [SECTION, Section.circular(1.0, 0.1, nu=0.3)])
    assert model.n_rotation_nodes == 5 and model.n_dofs == 18 + 15
    assert model.rotation_nodes.tolist() == [[0, 1, 3], [1, 2, 4]]
    with pytest.raises(ValueError, match="psi: expected shape"):
        model.evaluate(np.zeros(18), np.zeros((3, 3)))
    # an end triad turned against the middle one by more than the interpolation takes
    psi = np.zeros((5, 3))
    psi[2] = [0.0, 0.0, 3.12]
    with pytest.raises(RotationRangeError, match="elements 1") as info:
        model.evaluate(np.zeros(18), psi)
    assert info.value.elements.tolist() == [1]


def test_results_do_not_depend_on_the_thread_count():
    import numba
    beams = helix_beam(70, radius=1.0, turns=2.0)        # more than one chunk of elements
    model = SimoReissnerBeam(beams, SECTION)
    d, psi = deformed_state(model, seed=9, size=0.01, turn=0.05)
    threads = numba.get_num_threads()
    if threads < 2:
        pytest.skip("one Numba thread: nothing to compare with")
    try:
        numba.set_num_threads(1)
        f1, K1 = model.evaluate(d, psi)
        numba.set_num_threads(threads)
        f2, K2 = model.evaluate(d, psi)
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(f1, f2) and np.array_equal(K1.data, K2.data)


def test_reference_triads_of_joined_and_reversed_beams():
    """Several beams in one mesh each start their own transport; a beam whose elements are listed
    from its far end is transported from the node that already has a frame."""
    straight, arc = straight_beam(2), arc_beam(3)
    joined = BeamMesh.join([straight, arc])
    L = reference_triads(joined)
    n_s = straight.n_nodes
    # nodes of the arc (and its middle nodes) carry the arc's own frames
    arc_alone = reference_triads(arc)
    assert np.abs(L[n_s: n_s + arc.n_nodes] - arc_alone[: arc.n_nodes]).max() < 1e-15
    assert np.abs(L[joined.n_nodes + straight.n_elements:] - arc_alone[arc.n_nodes:]).max() < 1e-15
    # the helix with its elements listed backwards: the same frames up to the start node's choice
    helix = helix_beam(4)
    backwards = BeamMesh.hermite(helix.positions, helix.tangents, helix.elements[::-1])
    Lb = reference_triads(backwards)
    assert np.abs(np.einsum("kji,kjl->kil", Lb, Lb) - np.eye(3)).max() < 1e-14
    assert np.abs(Lb[: helix.n_nodes, :, 0] - helix.tangents).max() < 1e-15
    model = SimoReissnerBeam(backwards, SECTION)
    assert np.abs(model._K0[..., 0]).max() < 1.1e-2         # rotation-minimising from either end
