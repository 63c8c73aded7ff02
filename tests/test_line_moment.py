"""``type = "line_moment"``: a dead moment per reference length along a Simo–Reissner beam."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

import mortar1d3d as m13
from mortar1d3d import SceneError
from mortar1d3d.model import Model
from mortar1d3d.physics.simo_reissner import line_moment

from test_simo_reissner_model import cantilever, tip_positions


def _exact_tip(m, EI=1.0, L=1.0):
    """Cantilever under a uniform moment m per length about z: no force anywhere (n' = 0, n(L) = 0),
    so no stretch or shear, the bending moment m (L - s), the turn θ(s) = m (L s - s²/2)/EI, and
    the tip at ∫ (cos θ, sin θ) ds."""
    theta = lambda s: m * (L * s - 0.5 * s * s) / EI                     # noqa: E731
    x = quad(lambda s: math.cos(theta(s)), 0.0, L, epsabs=1e-14, epsrel=1e-14)[0]
    y = quad(lambda s: math.sin(theta(s)), 0.0, L, epsabs=1e-14, epsrel=1e-14)[0]
    return np.array([x, y, 0.0]), theta(L)


@pytest.mark.parametrize("elements, tolerance", [(8, 5e-5), (16, 1e-6)])
def test_cantilever_under_a_uniform_line_moment_matches_the_closed_form(elements, tolerance):
    """Measured: 3.7e-5 (8 elements), 6.2e-7 (16), 1.5e-3 (4); Newton 4 iterations per step."""
    m = 2.0                                                       # tip turn m L²/(2 EI) = 1 rad
    result = m13.solve(cantilever(elements, [{"type": "line_moment", "on": "beam:0", "value": [0, 0, m]}], steps=4))
    tip, turn = _exact_tip(m)
    assert np.linalg.norm(tip_positions(result)[-1] - tip) < tolerance
    assert result.beam_rotation[-1] == pytest.approx([0.0, 0.0, turn], abs=tolerance)
    # the moment along the beam is m (L - s): at the clamp the reaction is m L (no force)
    assert all(s.cuts == 0 for s in result.steps)
    assert np.abs(result.reactions[0]).max() < 1e-8 * m


def test_uniform_line_moment_about_the_axis_twists_linearly_in_s_squared():
    """Torsion: m about the beam's axis turns the section by θ(s) = m (L s - s²/2)/GI_T."""
    m, GI_T = 0.3, 0.7
    section = {"EA": 1e4, "GA2": 1e4, "GA3": 1e4, "GI_T": GI_T, "EI2": 1.0, "EI3": 1.0}
    result = m13.solve(cantilever(4, [{"type": "line_moment", "on": "beam:0", "value": [m, 0, 0]}], steps=1,
                                  section=section))
    s = np.linspace(0.0, 1.0, 5)
    np.testing.assert_allclose(result.beam_rotation[:, 0], m * (s - 0.5 * s * s) / GI_T, atol=1e-12)
    np.testing.assert_allclose(result.beam_rotation[:, 1:], 0.0, atol=1e-12)


def test_nodal_moments_sum_to_the_moment_times_the_length_on_a_curved_beam():
    scene = m13.Scene(beams=[{"curve": {"helix": {"centre": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.3,
                                                  "length": 1.2, "turns": 0.5}},
                              "elements": 5, "model": "simo_reissner", "section": {"E": 1.0, "nu": 0.3, "radius": 0.1}}],
                      dirichlet=[{"on": "beam:0:start", "clamp": True}])
    g = Model(scene).prepare().groups[0]
    nodes, moments = line_moment(g.physics, np.arange(5), [0.1, -0.2, 0.4])
    # Σ_k L_k = 1: the moments add up to m times the discrete centreline's length
    np.testing.assert_allclose(moments.sum(axis=0), g.mesh.lengths.sum() * np.array([0.1, -0.2, 0.4]), rtol=1e-9)
    assert g.mesh.lengths.sum() == pytest.approx(math.hypot(1.2, math.pi * 0.3), rel=1e-4)
    assert len(np.unique(nodes)) == g.physics.n_rotation_nodes


def test_line_moment_needs_a_whole_beam_with_rotations():
    with pytest.raises(SceneError, match=r"load\[0\].on: a line moment acts along a whole beam"):
        cantilever(2, [{"type": "line_moment", "on": "beam:0:end", "value": [0, 0, 1]}], steps=1)
    with pytest.raises(SceneError, match=r"load\[0\].on: a line moment needs a beam with rotations"):
        m13.Scene(beams=[{"curve": {"line": [[0, 0, 0], [1, 0, 0]]}, "elements": 2,
                          "section": {"EA": 1.0, "EI": 1.0}, "model": "torsion_free"}],
                  dirichlet=[{"on": "beam:0:start", "clamp": True}],
                  load=[{"type": "line_moment", "on": "beam:0", "value": [0, 0, 1]}])
