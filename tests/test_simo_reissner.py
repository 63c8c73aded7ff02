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


def chain(positions, tangents):
    n = len(positions) - 1
    return BeamMesh.hermite(positions, tangents, np.column_stack([np.arange(n), np.arange(1, n + 1)]))


def straight_beam(n, length=1.0, direction=(1.0, 0.0, 0.0)):
    s = np.linspace(0.0, length, n + 1)
    d = unit(direction)
    return chain(s[:, None] * d, np.tile(d, (n + 1, 1)))


def arc_beam(n, radius=1.0, angle=np.pi / 2):
    s = np.linspace(0.0, angle, n + 1)
    return chain(radius * np.column_stack([np.sin(s), 1 - np.cos(s), 0 * s]),
                 np.column_stack([np.cos(s), np.sin(s), 0 * s]))


def helix_beam(n, radius=0.3, pitch=0.1, turns=0.35):
    c = np.hypot(radius, pitch)
    s = np.linspace(0.0, 2 * np.pi * turns, n + 1)
    return chain(np.column_stack([radius * np.cos(s), radius * np.sin(s), pitch * s]),
                 np.column_stack([-radius * np.sin(s), radius * np.cos(s), pitch * np.ones_like(s)]) / c)


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


def test_tangent_against_central_differences():
    model = SimoReissnerBeam(helix_beam(3), SECTION)
    d, psi = deformed_state(model)
    f, K = model.evaluate(d, psi)
    K = K.toarray()
    fd = central_differences(lambda x: model.evaluate(*perturbed(model, d, psi, x), tangent=False)[0],
                             np.zeros(model.n_dofs), 1e-6).T
    assert np.abs(K - fd).max() < 1e-9 * np.abs(K).max()
    assert np.abs(K - K.T).max() > 1e-2 * np.abs(K).max()      # away from equilibrium: not symmetric


def test_residual_is_the_energy_derivative():
    model = SimoReissnerBeam(helix_beam(3), SECTION, n_gauss=3, force_gauss=2)
    d, psi = deformed_state(model, seed=2)
    f, _ = model.evaluate(d, psi, tangent=False)
    fd = central_differences(lambda x: model.energy(*perturbed(model, d, psi, x)), np.zeros(model.n_dofs), 1e-6)
    assert np.abs(f - fd).max() < 1e-8 * np.abs(f).max()
