"""Strain measures and det of physics/kinematics.py against their textbook numpy forms."""
import numpy as np
import pytest

from mortar1d3d.physics.kinematics import det3, green_lagrange, small_strain

VOIGT = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]


def gradients(count=20, seed=0):
    rng = np.random.default_rng(seed)
    return [scale * rng.uniform(-1.0, 1.0, (3, 3)) for scale in (1e-6, 1e-2, 0.5) for _ in range(count)]


@pytest.mark.parametrize("H", gradients(), ids=lambda H: f"|H|={np.abs(H).max():.0e}")
def test_green_lagrange_is_half_of_FtF_minus_I(H):
    F = np.eye(3) + H
    E = 0.5 * (F.T @ F - np.eye(3))
    got = green_lagrange(H)
    # (FᵀF - I)/2 loses the digits of H in 1 + H: compare at the size of that cancellation
    for value, (i, j) in zip(got, VOIGT):
        assert value == pytest.approx(E[i, j], rel=0, abs=1e-15 * (1.0 + np.abs(H).max()) ** 2)
    # ... and to the round-off of H itself against the same form without 1 + H
    exact = 0.5 * (H + H.T + H.T @ H)
    for value, (i, j) in zip(got, VOIGT):
        assert value == pytest.approx(exact[i, j], rel=0, abs=1e-15 * np.abs(H).max())


@pytest.mark.parametrize("H", gradients(5), ids=lambda H: f"|H|={np.abs(H).max():.0e}")
def test_small_strain_and_det(H):
    eps = 0.5 * (H + H.T)
    assert small_strain(H) == tuple(eps[i, j] for i, j in VOIGT)
    F = np.eye(3) + H
    assert det3(F) == pytest.approx(np.linalg.det(F), rel=1e-14)
    assert det3(np.diag([2.0, 3.0, -0.5])) == -3.0
